"""The Hillaire 2020 solver (`transport/hillaire.py`) against references outside it: the
transmittance table against the exponential atmosphere integrated by `scipy.integrate.quad`,
the multiple-scattering table against Hillaire's eqs. 5-9 evaluated independently in numpy for
a homogeneous shell (closed-form transmittance), the sky-view table against marching every ray,
and the sky against the Bruneton tables ("lut", itself within ~1 % of Monte Carlo) for Earth's
clear air. The solver contract itself is `test_solver_conformance.py`'s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from transport_cases import EARTH_RADIUS_M, exponential_earth, homogeneous_shell

from skyscatter import compile_ahead
from skyscatter.api import load_atmosphere
from skyscatter.transport import _hillaire_kernels, _kernels, hillaire
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.hillaire import MULTIPLE_SCATTERING_SIZE, HillaireSolver
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver
from skyscatter.transport.tables import precompute_tables

DEG = math.pi / 180.0
SCALE_HEIGHTS_M = np.array([8000.0, 1200.0])  # of exponential_earth's two constituents
TOP_M = 60_000.0


def exact_optical_depth(profile, r: float, mu: float) -> np.ndarray:
    """sum_c beta_e,c int_0^d exp(-h(t) / H_c) dt (n_wl,) from radius r along mu to the top
    of `exponential_earth`, h(t) = sqrt(r^2 + t^2 + 2 r mu t) - R."""
    top = EARTH_RADIUS_M + TOP_M
    d = -r * mu + math.sqrt(r * r * (mu * mu - 1.0) + top * top)
    columns = [quad(lambda t, h=h: math.exp(-(math.sqrt(r * r + t * t + 2 * r * mu * t)
                                              - EARTH_RADIUS_M) / h), 0.0, d,
                    limit=200, epsabs=0.0, epsrel=1e-10)[0] for h in SCALE_HEIGHTS_M]
    return np.array(columns) @ profile.extinction_per_density


def test_transmittance_table_matches_the_exponential_atmosphere():
    # Off-node (r, mu) from the ground to 23 km, zenith to 2 deg below the horizontal. The
    # table holds column densities on 64 x 256 nodes, linear in Bruneton's (x_r, x_mu); the
    # profile's densities are linear between 30 m levels (tau off by < 5e-5 relative).
    # Measured: at most 8.2e-4 relative in T at the grazing rays from the ground (mu = 0.005,
    # where the column changes fastest with mu), 1e-5 to 2e-4 elsewhere. Tolerance 1e-3.
    profile = exponential_earth()
    solver = HillaireSolver(profile)
    columns = np.empty(2)
    for altitude in (0.0, 1500.0, 7300.0, 23_000.0):
        r = EARTH_RADIUS_M + altitude
        for mu in (1.0, 0.71, 0.33, 0.1, 0.03, 0.005, -0.02):
            if mu < 0.0 and altitude == 0.0:
                continue
            _kernels.sun_columns(r, mu, profile.bottom_radius_m, profile.top_radius_m,
                                 solver.transmittance_columns, columns)
            table = np.exp(-columns @ profile.extinction_per_density)
            np.testing.assert_allclose(table, np.exp(-exact_optical_depth(profile, r, mu)),
                                       rtol=1e-3, err_msg=f"h={altitude} mu={mu}")


def shell_multiple_scattering(profile, r: float, mu_s: float) -> tuple[np.ndarray, ...]:
    """(L_2nd, f_ms) (n_wl,) of Hillaire 2020 eqs. 5-8 for the homogeneous isotropic shell of
    `homogeneous_shell` at radius r with the sun at zenith cosine mu_s (unit irradiance), on a
    dense quadrature of their own: Gauss-Legendre in the view's zenith cosine (split at the
    horizon) and in distance, midpoint in azimuth; transmittance exp(-sigma_t length) in closed
    form; a point sun, 0 where the planet hides it."""
    bottom, top = profile.bottom_radius_m, profile.top_radius_m
    sigma_t = profile.extinction_per_density[0]
    sigma_s = profile.scattering_per_density[0]
    albedo = profile.ground_albedo
    mu_h = -math.sqrt(max(r * r - bottom * bottom, 0.0)) / r
    x, w = np.polynomial.legendre.leggauss(96)
    mu = np.concatenate([mu_h + (1.0 - mu_h) * (x + 1) / 2, -1 + (mu_h + 1) * (x + 1) / 2])
    w_mu = np.concatenate([w * (1.0 - mu_h) / 2, w * (mu_h + 1) / 2])
    n_phi = 64
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    hits = mu < mu_h
    d_top = -r * mu + np.sqrt(r * r * (mu * mu - 1) + top * top)
    d_ground = -r * mu - np.sqrt(np.maximum(r * r * (mu * mu - 1) + bottom * bottom, 0.0))
    d = np.where(hits, d_ground, d_top)
    f_ms = 0.5 * np.sum(w_mu[:, None] * sigma_s / sigma_t * -np.expm1(-sigma_t * d[:, None]),
                        axis=0)  # (1 / 4 pi) int_0^2pi dphi = 1 / 2
    # L' per direction: march positions x_t = r z + t v
    sun = np.array([math.sqrt(1 - mu_s * mu_s), 0.0, mu_s])
    s, ws = np.polynomial.legendre.leggauss(64)
    sin_v = np.sqrt(1 - mu * mu)
    view = np.stack(np.broadcast_arrays(sin_v[:, None] * np.cos(phi), sin_v[:, None]
                                        * np.sin(phi), mu[:, None]), axis=-1)  # (n_mu, n_phi, 3)
    t = d[:, None] * (s + 1) / 2  # (n_mu, n_t)
    wt = d[:, None] * ws / 2
    points = np.array([0, 0, r]) + t[:, None, :, None] * view[:, :, None, :]

    def sunlight(p):
        radius = np.linalg.norm(p, axis=-1)
        cos_s = (p @ sun) / radius
        shadow = (cos_s < 0) & (radius * radius * (1 - cos_s * cos_s) < bottom * bottom)
        along = -radius * cos_s + np.sqrt(radius * radius * (cos_s * cos_s - 1) + top * top)
        return np.where(shadow, 0.0, 1.0)[..., None] * np.exp(-sigma_t * along[..., None])

    lit = (sigma_s / (4 * np.pi) * np.exp(-sigma_t * t[:, None, :, None])
           * sunlight(points))  # (n_mu, n_phi, n_t, n_wl)
    single = np.sum(wt[:, None, :, None] * lit, axis=2)
    ground_points = np.array([0, 0, r]) + d[:, None, None] * view
    ground_cos = (ground_points @ sun) / np.linalg.norm(ground_points, axis=-1)
    ground = (hits[:, None, None] * np.exp(-sigma_t * d[:, None])[:, None, :] * albedo / np.pi
              * sunlight(ground_points) * np.maximum(ground_cos, 0.0)[..., None])
    second = np.sum(w_mu[:, None, None] * (2 * np.pi / n_phi) * (single + ground),
                    axis=(0, 1)) / (4 * np.pi)
    return second, f_ms


@pytest.fixture(scope="module")
def shell():
    """A 10 km shell of extinction 2e-5 m^-1 (vertical optical depth 0.2), single-scattering
    albedo 0.9, isotropic, on a ground of albedo 0.3."""
    return homogeneous_shell(2e-5, albedo=0.3, single_scattering_albedo=0.9)


@pytest.mark.parametrize(("i_h", "j_mu_s"), [(0, 31), (0, 19), (16, 19), (22, 27), (26, 21)])
def test_multiple_scattering_table_is_the_papers_geometric_sum(shell, i_h, j_mu_s):
    # Nodes of the 32 x 32 table from the ground to 7 km, the sun from the zenith to 2 deg
    # above the horizon, against the reference's 192 x 64 directions and 64 Gauss nodes per
    # ray in closed form. The table's own quadrature is the paper's budget, 64 directions (4
    # Gauss zenith cosines on each side of the horizon x 8 azimuths) and 32 intervals per ray:
    # measured within 3.2 % for f_ms and 6.2 % for L_2nd and Psi_ms = L_2nd / (1 - f_ms) (the
    # worst at 7 km with the sun 6.6 deg high).
    # Tolerances 4 % and 8 %. (At the top node, where the rays just below the horizontal cross
    # the whole shell, f_ms is 12 % off; in a real atmosphere sigma_s ~ 0 there. With the sun
    # at or below the node's horizontal, 6.5 km up, L_2nd is 25-37 % off: its light comes
    # from the lit air by the horizon, which 4 zenith cosines resolve coarsely; 8 per side
    # take it to 5-19 %, yet move Earth's twilight sky 2 % further from the Monte Carlo
    # reference, docs/techniques.md.)
    solver = HillaireSolver(shell)
    r = solver.multiple_scattering_radii[i_h]
    mu_s = solver.multiple_scattering_sun_cosines[j_mu_s]
    second, f_ms = shell_multiple_scattering(shell, r, mu_s)
    print(f"h {r - shell.bottom_radius_m:.0f} mu_s {mu_s:.4f}: f_ms "
          f"{np.abs(solver.f_ms[i_h, j_mu_s] / f_ms - 1).max():.4f}, L_2nd "
          f"{np.abs(solver.second_order[i_h, j_mu_s] / second - 1).max():.4f}")
    np.testing.assert_allclose(solver.f_ms[i_h, j_mu_s], f_ms, rtol=0.04)
    np.testing.assert_allclose(solver.second_order[i_h, j_mu_s], second, rtol=0.08)
    np.testing.assert_allclose(solver.multiple_scattering[i_h, j_mu_s], second / (1 - f_ms),
                               rtol=0.08)


def test_the_multiple_scattering_nodes_invert_the_lookup_coordinates():
    # The nodes (`multiple_scattering_nodes`) must sit at the lookup's x = k / 31 on both axes
    # (`multiple_scattering_coordinates`), or every lookup reads a shifted table; and they
    # crowd where they should: altitude rows 0.1 km apart at the ground, sun columns within
    # 0.035 of each other between the sun setting for the ground (mu_s = 0) and for the top
    # (Earth: mu_s = -0.175, the sun 10 deg below the horizon). Round-off tolerance 1e-12.
    profile = load_atmosphere("earth").optical_profile([550.0])
    solver = HillaireSolver(profile)
    radii, cosines = solver.multiple_scattering_radii, solver.multiple_scattering_sun_cosines
    n_h, n_mu_s = MULTIPLE_SCATTERING_SIZE
    for k in range(max(n_h, n_mu_s)):
        x_h, x_mu = _hillaire_kernels.multiple_scattering_coordinates(
            radii[min(k, n_h - 1)], cosines[min(k, n_mu_s - 1)], profile.bottom_radius_m,
            profile.top_radius_m, solver._mu_s_centre)
        assert abs(x_h - min(k, n_h - 1) / (n_h - 1)) < 1e-12
        assert abs(x_mu - min(k, n_mu_s - 1) / (n_mu_s - 1)) < 1e-12
    assert radii[1] - radii[0] < 150.0 and radii[0] == profile.bottom_radius_m
    assert cosines[0] == -1.0 and cosines[-1] == 1.0
    setting = (cosines > -0.175) & (cosines < 0.0)
    assert setting.sum() >= 6 and np.diff(cosines[setting]).max() < 0.035


def test_multiple_scattering_kernel_converges_to_the_papers_formula(shell):
    # The same kernel with a fine quadrature (16 Gauss zenith cosines per side of the horizon
    # x 32 azimuths, 128 intervals per ray) on 3 altitudes x 9 sun zenith cosines: at the
    # ground and at 5 km with the sun 14.5 deg high to the zenith, measured within 1.2e-4 of
    # the independent evaluation (the rest: the transmittance table to the sun). Tolerance
    # 1e-3. (With the sun on the horizon the table's grazing transmittance is 1-3 % off.)
    solver = HillaireSolver(shell)
    gauss_x, gauss_w = np.polynomial.legendre.leggauss(16)
    psi, second, f_ms = _hillaire_kernels.multiple_scattering_table(
        shell.bottom_radius_m + np.array([0.0, 5000.0, 10_000.0]), np.linspace(-1.0, 1.0, 9),
        gauss_x, gauss_w, 32, 128, shell.bottom_radius_m, shell.top_radius_m, 50.0,
        shell.density, shell.extinction_per_density, shell.scattering_per_density,
        solver.transmittance_columns, shell.ground_albedo, 0.0)
    for i in (0, 1):
        for j in (5, 6, 8):
            reference_second, reference_f = shell_multiple_scattering(
                shell, shell.bottom_radius_m + 5000.0 * i, -1.0 + 0.25 * j)
            np.testing.assert_allclose(f_ms[i, j], reference_f, rtol=1e-3)
            np.testing.assert_allclose(second[i, j], reference_second, rtol=1e-3)
            np.testing.assert_allclose(psi[i, j], reference_second / (1 - reference_f),
                                       rtol=1e-3)


@pytest.mark.parametrize("sun_zenith_deg", [0.0, 45.0, 80.0, 93.0])
def test_the_sky_view_table_adds_little_to_marching_every_ray(monkeypatch, sun_zenith_deg):
    # 4 000 views of the upper hemisphere from the ground of `exponential_earth` (Rayleigh +
    # HG 0.8 haze), read from the 192 x 108 sky-view table against the same solver marching
    # each ray. Measured on Earth's preset (HG 0.65) at 256 x 256 fisheye pixels: median 3e-4,
    # 95th percentile <= 1.7e-3, at most 5e-3 by day and 1.5e-2 in twilight (the Earth's
    # shadow by the horizon); here 95th percentile <= 2.2e-3, at most 1.5e-2 by day (next to
    # the sun, in the haze's sharper peak) and 4.7e-2 in twilight (the Earth's shadow 4.5 deg
    # above the horizon opposite the sun, between rows: 2.6e-2 when Psi_ms, read linearly
    # between sun zenith cosines 0.065 apart, smeared it). Tolerances: 95th percentile 3e-3,
    # at most 6e-2.
    solver = HillaireSolver(exponential_earth())
    rng = np.random.default_rng(5)
    views = local_frame_directions(np.arccos(rng.uniform(0.0, 1.0, 4000)),
                                   rng.uniform(0.0, 2 * np.pi, 4000))
    sun = local_frame_directions(sun_zenith_deg * DEG, 0.7)
    ground = np.array([0.0, 0.0, EARTH_RADIUS_M])
    monkeypatch.setattr(hillaire, "SKY_VIEW_MIN_RAYS", 1)
    from_table = solver.sky_radiance(ground, views, sun)
    monkeypatch.setattr(hillaire, "SKY_VIEW_MIN_RAYS", 10**9)
    marched = solver.sky_radiance(ground, views, sun)
    error = np.abs(from_table / marched - 1.0)
    assert np.percentile(error, 95) < 3e-3 and error.max() < 6e-2


@pytest.fixture(scope="module")
def earth_solvers():
    """(hillaire, lut) for Earth's clear air (the "earth" preset: air, ozone, SPECTRL2's rural
    aerosol, ground albedo 0.1) at 440, 550 and 680 nm; Bruneton's tables at their default
    size and the preset's 8 orders (about 75 s)."""
    atmosphere = load_atmosphere("earth")
    profile = atmosphere.optical_profile([440.0, 550.0, 680.0])
    tables = precompute_tables(profile, None, atmosphere.scattering_orders)
    return HillaireSolver(profile), LutSolver(profile, tables=tables)


def difference_from_tables(hillaire_solver, lut, sun_zenith_deg: float) -> np.ndarray:
    """|L_hillaire / L_lut - 1| (49, 3) from the ground: 7 view zeniths (0-89 deg) x 7
    azimuths from the sun (0-180 deg)."""
    zenith, azimuth = np.meshgrid([0.0, 20.0, 40.0, 60.0, 75.0, 85.0, 89.0],
                                  np.linspace(0.0, 180.0, 7), indexing="ij")
    views = local_frame_directions(zenith * DEG, azimuth * DEG)
    sun = local_frame_directions(sun_zenith_deg * DEG, 0.0)
    ground = np.array([0.0, 0.0, lut.profile.bottom_radius_m])
    return np.abs(hillaire_solver.sky_radiance(ground, views, sun)
                  / lut.sky_radiance(ground, views, sun) - 1.0)


# sun zenith [deg] -> (median, 95th percentile) of |L_hillaire / L_lut - 1| allowed
AGAINST_TABLES = {0.0: (0.036, 0.09), 45.0: (0.056, 0.155), 80.0: (0.065, 0.245)}


@pytest.mark.slow
@pytest.mark.parametrize("sun_zenith_deg", list(AGAINST_TABLES))
def test_earth_sky_is_near_the_bruneton_tables(earth_solvers, sun_zenith_deg):
    # 7 view zeniths (0-89 deg) x 7 azimuths from the sun (0-180 deg), 3 wavelengths, from the
    # ground. Measured |relative difference|, median / 95th percentile / max: sun at the
    # zenith 3.0 / 7.5 / 8.8 %, at 45 deg 4.7 / 12.8 / 16.2 %, at 80 deg 5.4 / 20.3 / 28.1 %,
    # the Hillaire sky the darker by the horizon. The cause is the paper's approximation of
    # orders >= 2 (isotropic phase functions, laterally uniform light): the same comparison
    # with an isotropic aerosol gave 95th percentiles of 2.6 / 4.2 / 7.9 %, and air alone on
    # a black ground 4.1 / 3.7 / 4.5 % (with the paper's uniform table), while the single
    # scattering agrees with the "single" solver within 0.1 %. Tolerances: the measured
    # median and 95th percentile plus ~20 %.
    error = difference_from_tables(*earth_solvers, sun_zenith_deg)
    median, p95 = AGAINST_TABLES[sun_zenith_deg]
    print(f"sun {sun_zenith_deg}: median {np.median(error):.4f}, "
          f"p95 {np.percentile(error, 95):.4f}, max {error.max():.4f}")
    assert np.median(error) < median and np.percentile(error, 95) < p95


# sun zenith [deg] -> (median, 95th percentile) of |L_hillaire / L_lut - 1| allowed
TWILIGHT_AGAINST_TABLES = {94.0: (0.085, 0.43), 96.0: (0.145, 0.65)}


@pytest.mark.slow
@pytest.mark.parametrize("sun_zenith_deg", list(TWILIGHT_AGAINST_TABLES))
def test_earth_twilight_sky_is_near_the_bruneton_tables(earth_solvers, sun_zenith_deg):
    # The views and wavelengths of the daytime test with the sun 4 and 6 deg below the
    # horizon, where Psi_ms falls by orders of magnitude between sun zenith cosines a few
    # hundredths apart. Measured median / 95th percentile: 7.0 / 36.0 % at 94 deg and
    # 12.1 / 54.0 % at 96 deg; the paper's 32 columns uniform in mu_s, read linearly, gave
    # 64 / 209 % and 20.5 / 53 % (the sky up to 3.7 times too bright). The rest is the
    # method's: against the Monte Carlo reference at 94 deg (docs/techniques.md) Hillaire is
    # 12.7 % off in the median (14.3 % with a converged table of 1001 sun columns), "lut"
    # 5.1 %. Tolerances: the measured values plus ~20 %.
    error = difference_from_tables(*earth_solvers, sun_zenith_deg)
    median, p95 = TWILIGHT_AGAINST_TABLES[sun_zenith_deg]
    print(f"sun {sun_zenith_deg}: median {np.median(error):.4f}, "
          f"p95 {np.percentile(error, 95):.4f}, max {error.max():.4f}")
    assert np.median(error) < median and np.percentile(error, 95) < p95


def test_the_warm_up_compiles_the_sky_view_table():
    # `skyscatter compile` renders a panorama with the Hillaire solver: its rays must be
    # enough for the sky-view table (`SKY_VIEW_MIN_RAYS`), whose kernels compile only then
    command = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                   if "hillaire" in arguments)
    assert "panorama" in command
    size = int(command[command.index("--size") + 1])
    assert size * (2 * size) >= hillaire.SKY_VIEW_MIN_RAYS


@pytest.mark.parametrize("sun_zenith_deg", [0.0, 80.0, 93.0])
def test_without_multiple_scattering_it_is_the_single_scattering_solver(monkeypatch,
                                                                        sun_zenith_deg):
    # Psi_ms set to 0 leaves single scattering and the sunlit ground, which the "single" solver
    # marches on its own (its sun columns from a finer table, 128 x 256 nodes of 512
    # intervals). Views 0-120 deg from the zenith (the ground from 95 deg), 64 samples each.
    # Measured: within 4.3e-5 relative with the sun at the zenith, 2.2e-4 at 80 deg, 4.6e-4 in
    # twilight (where both give 0 on the unlit ground). Tolerance 1e-3.
    profile = exponential_earth()
    solver = HillaireSolver(profile)
    monkeypatch.setattr(solver, "multiple_scattering", np.zeros_like(solver.multiple_scattering))
    views = local_frame_directions(*np.broadcast_arrays(
        np.radians([[0.0], [45.0], [80.0], [89.0], [95.0], [120.0]]),
                                   np.radians([0.0, 90.0, 180.0])))
    sun = local_frame_directions(sun_zenith_deg * DEG, 0.0)
    ground = np.array([0.0, 0.0, EARTH_RADIUS_M])
    single = SingleScatteringSolver(profile, n_samples=64).sky_radiance(ground, views, sun)
    np.testing.assert_allclose(solver.sky_radiance(ground, views, sun), single, rtol=1e-3)
