"""Sunlight on the eclipsed Moon (render/lunar_eclipse.py): closed-form shadow edges, Monte Carlo
overlap of the solar disk, the point-source focusing law, and an exponential atmosphere's red
umbra compared with observed eclipse brightness."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from skyscatter.astro.moon_phase import shadow_radii_rad
from skyscatter.errors import InputError
from skyscatter.render import lunar_eclipse as le

R = 6_371_000.0  # m, test Earth
D_MOON = 384_400_000.0  # m
D_SUN = 1.495978707e11  # m
SUN = np.array([-D_SUN, 0.0, 0.0])  # Sun on -x: the shadow axis is +x
WL = np.array([450.0, 550.0, 600.0, 650.0, 700.0])
N0_MINUS_1, H = 2.9e-4, 8000.0  # sea-level refractivity; scale height [m]
GRAZING = math.sqrt(2.0 * math.pi * R / H)  # Chapman grazing air mass of the full chord
TAU_550 = 0.097  # Rayleigh vertical optical depth at 550 nm (Bodhaine et al. 1999)


def deflection(h):
    """Exponential atmosphere: δ(h) = (n0 - 1) √(2πR/H) e^{-h/H} (e.g. Link 1969 ch. 2)."""
    return N0_MINUS_1 * GRAZING * np.exp(-np.asarray(h) / H)


def rayleigh_transmittance(h):
    """T = exp(-τ_R(λ) √(2πR/H) e^{-h/H}), τ_R ∝ λ^-4 normalised to 0.097 at 550 nm."""
    tau = TAU_550 * (550.0 / WL) ** 4
    return np.exp(-tau[None, :] * GRAZING * np.exp(-np.asarray(h)[:, None] / H))


def opaque(h):
    return np.zeros((np.size(h), WL.size))


def points_at(theta, distance=D_MOON):
    """Points at geocentric angle θ [rad] from the shadow axis."""
    theta = np.atleast_1d(theta)
    return distance * np.stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)], -1)


def test_circle_overlap_area_closed_forms():
    assert le.circle_overlap_area(1.0, 2.0, 0.5) == pytest.approx(np.pi)  # inside
    assert le.circle_overlap_area(1.0, 1.0, 2.0) == 0.0  # touching
    # two unit circles at distance 1: 2π/3 - √3/2 (MathWorld)
    assert le.circle_overlap_area(1.0, 1.0, 1.0) == pytest.approx(2 * np.pi / 3 - 3**0.5 / 2)
    assert le.circle_overlap_area(np.ones((2, 3)), 1.5, 0.7).shape == (2, 3)


def test_no_atmosphere_gives_the_closed_form_umbra_and_penumbra():
    # T = 0: the occulter is the disk of radius R + h_top. Edges: the cones of astro.moon_phase
    # (ρ = π_1 + π_s ∓ s, no enlargement) for that radius; their asin forms are exact to ~1e-7
    # rad, so points 1e-5 rad inside/outside must be fully dark/lit.
    top = 50_000.0
    rho_u, rho_p = shadow_radii_rad(D_MOON, D_SUN, "none", earth_radius_m=R + top)
    theta = np.array([0.0, 0.5 * rho_u, rho_u - 1e-5, rho_p + 1e-5, 2 * rho_p])
    c = le.eclipse_factor(points_at(theta), SUN, opaque, deflection, earth_radius_m=R,
                          top_altitude_m=top)
    np.testing.assert_array_equal(c[:3], 0.0)
    np.testing.assert_array_equal(c[3:], 1.0)


def test_penumbra_matches_monte_carlo_overlap_of_the_solar_disk():
    # Reference: 400 000 uniform samples of the solar disk seen from P, each tested for lying
    # behind the Earth's disk (spherical angles, no small-angle formula). Tolerance 0.005
    # (absolute): Monte Carlo noise 0.0008 (1σ) + planar approximation ~1e-4.
    top = 50_000.0
    rho_u, rho_p = shadow_radii_rad(D_MOON, D_SUN, "none", earth_radius_m=R + top)
    theta = rho_u + (rho_p - rho_u) * np.array([0.1, 0.35, 0.5, 0.8])
    points = points_at(theta)
    c = le.eclipse_factor(points, SUN, opaque, deflection, earth_radius_m=R,
                          top_altitude_m=top)[:, 0]
    rng = np.random.default_rng(7)
    n = 400_000
    for k, p in enumerate(points):
        to_sun = SUN - p
        d = np.linalg.norm(to_sun)
        axis = to_sun / d
        u = np.cross(axis, [0.0, 0.0, 1.0])
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        s = math.asin(6.957e8 / d)
        rad = s * np.sqrt(rng.random(n))
        ang = 2 * np.pi * rng.random(n)
        dirs = (np.cos(rad)[:, None] * axis + np.sin(rad)[:, None]
                * (np.cos(ang)[:, None] * u + np.sin(ang)[:, None] * v))
        to_earth = -p / np.linalg.norm(p)
        beta = math.asin((R + top) / np.linalg.norm(p))
        hidden = dirs @ to_earth > math.cos(beta)
        assert c[k] == pytest.approx(1.0 - hidden.mean(), abs=0.005)


def test_transparent_non_refracting_atmosphere_reduces_to_the_bare_earth():
    # Identity: with T = 1 and δ = 0 the refracted integral (b) must fill in the annulus
    # R..R+h_top exactly as straight rays do, so C equals (a) for the bare Earth (h_top = 0).
    # Tolerance 2e-3: midpoint sum over the altitude cells against the exact lens area.
    rho_u, rho_p = shadow_radii_rad(D_MOON, D_SUN, "none", earth_radius_m=R)
    theta = np.linspace(0.8 * rho_u, 1.05 * rho_p, 12)
    clear = le.eclipse_factor(points_at(theta), SUN, lambda h: np.ones((h.size, 1)),
                              lambda h: np.zeros(h.size), earth_radius_m=R,
                              top_altitude_m=100_000.0)
    bare = le.eclipse_factor(points_at(theta), SUN, lambda h: np.ones((h.size, 1)),
                             lambda h: np.zeros(h.size), earth_radius_m=R, top_altitude_m=0.0,
                             altitude_edges_m=[0.0, 1e-3])
    np.testing.assert_allclose(clear, bare, atol=2e-3)


def test_small_sun_reproduces_the_point_source_focusing_factor():
    # Reference: the point-source law of the brief / Link (1969): at distance ρ from the axis,
    # C = Σ_roots T(h) (R + h) / (ρ |dρ/dh|), ρ(h) = ±ρ_P with ρ(h) = (R + h) - D δ(h) (small
    # angles), roots found with scipy's brentq. Ours: a Sun shrunk to 0.005 of its radius, 1 m
    # altitude cells. Tolerance 2 %: small-angle ρ(h) vs asin (measured <= 1.5 %, at 450 nm
    # where T changes fastest with h); with a 0.02 Sun the root at h = 15 m is cut by the ground.
    sun_radius = 0.005 * 6.957e8
    edges = np.arange(0.0, 40_000.0 + 1.0, 1.0)
    for rho in (0.3 * 1.737e6, 1.5e6, 3.0e6):
        theta = rho / D_MOON
        c = le.eclipse_factor(points_at(theta), SUN, rayleigh_transmittance, deflection,
                              earth_radius_m=R, sun_radius_m=sun_radius, top_altitude_m=40e3,
                              altitude_edges_m=edges)[0]
        # P at distance D along the axis: ρ(h) measured in the plane at distance D
        dist = D_MOON * math.cos(theta)

        def miss(h, target, dist=dist):
            return R + h - dist * deflection(h) - target  # ρ(h) - target

        expected = np.zeros(WL.size)
        for sign in (1.0, -1.0):
            if miss(0.0, sign * rho) * miss(40e3, sign * rho) < 0.0:
                h0 = brentq(miss, 0.0, 40e3, args=(sign * rho,), xtol=1e-6)
                slope = 1.0 + dist * N0_MINUS_1 * GRAZING / H * math.exp(-h0 / H)
                expected += rayleigh_transmittance([h0])[0] * (R + h0) / (rho * slope)
        assert np.all(expected > 0.0)
        np.testing.assert_allclose(c, expected, rtol=0.02)


def test_exponential_atmosphere_reddens_and_dims_the_umbra():
    # Published: in partial eclipses the penumbral part of the disk is ~500x brighter than the
    # umbral limb (Espenak & Meeus 2009, Five Millennium Canon of Lunar Eclipses, NASA/TP-2009-
    # 214172, "Visual appearance"), i.e. ~1e-3 of full sunlight just inside the umbra, and the
    # centre of the umbra is darker still (~1e-4, Danjon L = 2-3). Our test atmosphere has no
    # clouds, aerosols or ozone, so it sits at the bright end: the check is an order of
    # magnitude only, 1e-5 < C(600 nm, centre) < 1e-2 and 1e-4 < C(550 nm, 0.9 ρ_u) < 1e-2
    # (measured 4.8e-4 and 1.6e-3), with strong reddening C(650)/C(450) > 100 at the centre
    # (Rayleigh τ ∝ λ⁻⁴ along a ~70-air-mass grazing path; measured 2900).
    c = le.eclipse_factor(points_at(0.0), SUN, rayleigh_transmittance, deflection,
                          earth_radius_m=R)[0]
    i450, i550, i600, i650 = 0, 1, 2, 3
    assert 1e-5 < c[i600] < 1e-2
    assert c[i650] / c[i450] > 100.0
    assert np.all(np.diff(c) > 0.0)  # redder is brighter at every step
    rho_u, _ = shadow_radii_rad(D_MOON, D_SUN, "none", earth_radius_m=R)
    edge = le.eclipse_factor(points_at(0.9 * rho_u), SUN, rayleigh_transmittance, deflection,
                             earth_radius_m=R)[0]
    assert 1e-4 < edge[i550] < 1e-2


def test_refraction_brightens_the_umbra_towards_its_edge_smoothly():
    rho_u, rho_p = shadow_radii_rad(D_MOON, D_SUN, "none", earth_radius_m=R)
    theta = np.linspace(0.0, rho_p * 1.1, 60)
    c = le.eclipse_factor(points_at(theta), SUN, rayleigh_transmittance, deflection,
                          earth_radius_m=R)[:, 2]
    assert np.all(np.isfinite(c)) and np.all(c > 0.0) and np.all(c <= 1.0 + 1e-9)
    inner = theta < 0.6 * rho_u
    assert c[inner].max() < 0.05 and c[-1] == pytest.approx(1.0)


def test_4000_scattered_points_give_finite_factors():
    # 4000 moon pixels with the default ~560 altitude cells: finite and of the right shape.
    # (35-70 ms on 2 cores; timings are benchmarked, not asserted: STYLE.)
    rng = np.random.default_rng(3)
    theta = rng.uniform(0.0, 0.02, 4000)
    points = points_at(theta) + rng.normal(size=(4000, 3)) * 1e6
    c = le.eclipse_factor(points, SUN, rayleigh_transmittance, deflection, earth_radius_m=R)
    assert c.shape == (4000, WL.size) and np.all(np.isfinite(c))


def test_bad_inputs_raise_input_error():
    with pytest.raises(InputError, match="above the atmosphere"):
        le.eclipse_factor([[R, 0.0, 0.0]], SUN, opaque, deflection, earth_radius_m=R)
    with pytest.raises(InputError, match="sun_geocentric_m"):
        le.eclipse_factor(points_at(0.0), SUN[:2], opaque, deflection)
    with pytest.raises(InputError, match="grazing_transmittance"):
        le.eclipse_factor(points_at(0.0), SUN, lambda h: np.ones(h.size), deflection)
