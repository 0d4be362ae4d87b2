"""Point stars, scintillation, air mass and the integrated starlight (skyscatter.render.stars)."""

import math

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.render.camera import EquirectangularCamera, FisheyeCamera, PerspectiveCamera
from skyscatter.render.stars import (
    ICRS_TO_GALACTIC,
    INTEGRATED_STARLIGHT_PLANE_S10,
    INTEGRATED_STARLIGHT_POLE_S10,
    S10_RADIANCE_V,
    add_star_background,
    add_stars,
    airmass_kasten_young_1989,
    integrated_starlight_radiance,
    scintillation_factors,
)
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.spectrum.magnitudes import v_band_mean

N_WL = 4
CAMERAS = {
    "fisheye": FisheyeCamera(97),
    "fisheye-small": FisheyeCamera(8),
    "perspective": PerspectiveCamera(120, 80, 60.0, heading_deg=30.0, pitch_deg=40.0,
                                     roll_deg=10.0),
    "panorama": EquirectangularCamera(90, 45, heading_deg=20.0),
}


def random_up_directions(rng, n):
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 1e-3
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("name", sorted(CAMERAS))
def test_each_star_inside_the_image_keeps_its_flux_exactly(name):
    # Identity (eq. 1): Σ_p L_p Ω_p = E T per star, whatever the projection and resolution.
    camera = CAMERAS[name]
    rng = np.random.default_rng(7)
    directions = random_up_directions(rng, 400)
    irradiance = rng.uniform(0.5, 2.0, size=(400, N_WL)) * 1e-9
    transmittance = rng.uniform(0.2, 1.0, size=(400, N_WL))
    omega = camera.pixel_solid_angles()
    valid = camera.valid_mask()
    deposited = 0
    for k in range(400):  # one star at a time, to check each one
        image = np.zeros((camera.height, camera.width, N_WL))
        count = add_stars(image, camera, valid, directions[k:k + 1], irradiance[k:k + 1],
                          transmittance=transmittance[k:k + 1])
        total = np.einsum("hwk,hw->k", image, omega)
        if count:
            deposited += 1
            np.testing.assert_allclose(total, irradiance[k] * transmittance[k], rtol=1e-9)
            assert np.all(image[~valid] == 0.0)
        else:
            assert np.all(total == 0.0)
    assert deposited > 40  # the test saw stars in every image


def test_many_stars_at_once_equal_the_sum_of_single_stars():
    camera = FisheyeCamera(64)
    rng = np.random.default_rng(3)
    directions = random_up_directions(rng, 300)
    irradiance = rng.uniform(size=(300, N_WL))
    together = np.zeros((64, 64, N_WL))
    add_stars(together, camera, camera.valid_mask(), directions, irradiance, transmittance=1.0)
    apart = np.zeros((64, 64, N_WL))
    for k in range(300):
        add_stars(apart, camera, camera.valid_mask(), directions[k:k + 1], irradiance[k:k + 1],
                  transmittance=1.0)
    np.testing.assert_allclose(together, apart, rtol=1e-12, atol=0.0)


def test_star_at_a_pixel_centre_goes_into_that_pixel():
    camera = FisheyeCamera(9)
    directions, valid = camera.directions()
    image = np.zeros((9, 9, 1))
    add_stars(image, camera, valid, directions[4, 4][None], np.ones((1, 1)), transmittance=1.0)
    omega = camera.pixel_solid_angles()
    assert image[4, 4, 0] == pytest.approx(1.0 / omega[4, 4], rel=1e-9)
    assert np.count_nonzero(image) == 1


def test_stars_below_horizon_or_behind_camera_are_skipped():
    image = np.zeros((10, 10, 1))
    camera = FisheyeCamera(10)
    below = np.array([[0.0, 0.6, -0.8], [1.0, 0.0, 0.0]])
    assert add_stars(image, camera, camera.valid_mask(), below, np.ones((2, 1)),
                     transmittance=1.0) == 0
    behind = PerspectiveCamera(10, 10, 40.0, heading_deg=0.0, pitch_deg=10.0)
    back = np.array([[0.0, -0.9, 0.3]])
    assert add_stars(image, behind, behind.valid_mask(), back, np.ones((1, 1)),
                     transmittance=1.0) == 0
    assert not image.any()


def test_transmittance_and_scintillation_multiply():
    camera = FisheyeCamera(16)
    d = np.array([[0.1, 0.2, 0.97]])
    a, b = np.zeros((16, 16, 2)), np.zeros((16, 16, 2))
    add_stars(a, camera, camera.valid_mask(), d, np.ones((1, 2)), transmittance=1.0)
    add_stars(b, camera, camera.valid_mask(), d, np.ones((1, 2)),
              transmittance=np.array([[0.5, 0.25]]), scintillation=np.array([2.0]))
    np.testing.assert_allclose(b[..., 0], a[..., 0])
    np.testing.assert_allclose(b[..., 1], 0.5 * a[..., 1])


def test_add_stars_errors():
    camera = FisheyeCamera(8)
    image = np.zeros((8, 8, 3))
    with pytest.raises(InputError, match="star_irradiance must have shape"):
        add_stars(image, camera, camera.valid_mask(), np.zeros((2, 3)), np.ones((2, 2)),
                  transmittance=1.0)
    with pytest.raises(InputError, match=r"shape \(n, 3\)"):
        add_stars(image, camera, camera.valid_mask(), np.zeros((2, 2)), np.ones((2, 3)),
                  transmittance=1.0)


# --- air mass and scintillation ------------------------------------------------------------------

def test_kasten_young_airmass_published_values():
    # Kasten & Young (1989): X(0°) = 1 (formula 0.9997), X(60°) ≈ 2 (plane-parallel 1/cos z,
    # curvature + refraction −0.2 %), horizon 37.92 (their quoted value for the formula;
    # their table: 38.09). Tolerances: 0.05 %, 0.5 %, 0.01.
    x = airmass_kasten_young_1989([0.0, 60.0, 90.0])
    assert x[0] == pytest.approx(1.0, rel=5e-4)
    assert x[1] == pytest.approx(2.0, rel=5e-3)
    assert x[2] == pytest.approx(37.92, abs=0.01)
    assert np.all(np.diff(airmass_kasten_young_1989(np.linspace(0, 90, 91))) > 0)
    with pytest.raises(InputError, match="zenith_deg"):
        airmass_kasten_young_1989(95.0)


def test_scintillation_mean_is_one_and_sigma_grows_with_airmass():
    rng = np.random.default_rng(11)
    n = 200_000
    zenith = scintillation_factors(np.ones(n), rng)
    low = scintillation_factors(np.full(n, 1.5), rng)
    # Young (1967) with D = 0.7 cm, t = 0.1 s, h = 0: σ = 0.09 · 0.7^(-2/3) / sqrt(0.2) = 0.2553
    # at X = 1; × 1.5^1.75 = 0.5191 at X = 1.5. Tolerance: 4 standard errors of the estimate.
    assert zenith.mean() == pytest.approx(1.0, abs=4 * 0.2553 / math.sqrt(n))
    assert low.mean() == pytest.approx(1.0, abs=4 * 0.5191 / math.sqrt(n))
    # σ via the log-normal's log: std(ln f) = sqrt(ln(1 + σ²)) (a sharper estimate than std f).
    assert np.log(zenith).std() == pytest.approx(math.sqrt(math.log1p(0.2553**2)), rel=0.01)
    assert np.log(low).std() == pytest.approx(math.sqrt(math.log1p(0.5191**2)), rel=0.01)
    assert np.all(zenith > 0.0)
    saturated = scintillation_factors(np.full(n, 10.0), rng)
    assert saturated.mean() == pytest.approx(1.0, abs=0.02)
    assert np.log(saturated).std() == pytest.approx(math.sqrt(math.log(2.0)), rel=0.02)


def test_scintillation_shapes_and_errors():
    rng = np.random.default_rng(0)
    for shape in [(), (5,), (2, 3)]:
        assert scintillation_factors(np.ones(shape), rng).shape == shape
    with pytest.raises(InputError, match="airmass"):
        scintillation_factors(0.5, rng)


# --- integrated starlight ------------------------------------------------------------------------

def test_galactic_matrix_maps_pole_and_centre():
    # ESA (1997) Vol. 1 §1.5.3: NGP at α = 192.85948°, δ = 27.12825°; galactic centre at
    # α = 266.40500°, δ = -28.93617° (ICRS). Tolerance 1e-6 rad (the matrix has 10 digits).
    def unit(ra, dec):
        ra, dec = math.radians(ra), math.radians(dec)
        return np.array([math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra),
                         math.sin(dec)])
    np.testing.assert_allclose(ICRS_TO_GALACTIC @ unit(192.85948, 27.12825), [0, 0, 1],
                               atol=1e-6)
    np.testing.assert_allclose(ICRS_TO_GALACTIC @ unit(266.40500, -28.93617), [1, 0, 0],
                               atol=1e-6)
    np.testing.assert_allclose(ICRS_TO_GALACTIC @ ICRS_TO_GALACTIC.T, np.eye(3), atol=1e-9)


def galactic_directions(b_deg, count=2000):
    l_rad = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    b_rad = np.full_like(l_rad, math.radians(b_deg))
    gal = np.stack([np.cos(b_rad) * np.cos(l_rad), np.cos(b_rad) * np.sin(l_rad),
                    np.sin(b_rad)], axis=1)
    return gal @ ICRS_TO_GALACTIC  # back to ICRS


def test_integrated_starlight_reproduces_its_anchors():
    # Leinert et al. (1998) §10 anchors: 25 S10 averaged over |b| > 80°, 250 S10 over |b| < 5°
    # (stars fainter than V = 6). Ours: the map averaged over uniform random directions in the
    # same bands (equal-area sampling, as the calibration). Tolerance 5 %: bilinear
    # interpolation between map cells + sampling noise.
    grid = wavelength_grid(16)
    rng = np.random.default_rng(5)
    icrs = rng.normal(size=(400_000, 3))
    icrs /= np.linalg.norm(icrs, axis=1, keepdims=True)
    sin_b = (icrs @ ICRS_TO_GALACTIC.T)[:, 2]
    s10 = v_band_mean(grid, integrated_starlight_radiance(icrs, grid)) / S10_RADIANCE_V
    # v_band_mean on the 16-bin grid reads cells as constant: 0.1 % off the exact V mean.
    poles = s10[np.abs(sin_b) > math.sin(math.radians(80.0))].mean()
    plane = s10[np.abs(sin_b) < math.sin(math.radians(5.0))].mean()
    assert poles == pytest.approx(INTEGRATED_STARLIGHT_POLE_S10, rel=0.05)
    assert plane == pytest.approx(INTEGRATED_STARLIGHT_PLANE_S10, rel=0.05)
    assert np.all(np.isfinite(s10)) and np.all(s10 > 0.0)
    plane_circle = integrated_starlight_radiance(galactic_directions(0.0), grid)
    assert plane_circle.mean() > 10.0 * integrated_starlight_radiance(
        galactic_directions(85.0), grid).mean()


def test_drawn_stars_are_removed_from_the_glow():
    grid = wavelength_grid(8)
    d = galactic_directions(0.0, 500)
    faint_limit = integrated_starlight_radiance(d, grid, rendered_limit_v=9.0)
    bright_limit = integrated_starlight_radiance(d, grid, rendered_limit_v=6.0)
    assert np.all(faint_limit <= bright_limit + 1e-30)
    assert faint_limit.mean() < 0.95 * bright_limit.mean()
    assert np.all(faint_limit >= 0.0)


def test_s10_radiance_value():
    # 1 S10 = one V = 10 star per square degree: 3.631e-11 × 1e-4 / (π/180)² sr.
    assert pytest.approx(1.1920e-11, rel=1e-4) == S10_RADIANCE_V


@pytest.mark.parametrize("shape", [(3,), (5, 3), (2, 4, 3)])
def test_integrated_starlight_shapes(shape):
    rng = np.random.default_rng(2)
    grid = wavelength_grid(6)
    result = integrated_starlight_radiance(rng.normal(size=shape), grid)
    assert result.shape == shape[:-1] + (6,)
    assert np.all(np.isfinite(result)) and np.all(result >= 0.0)


def test_add_star_background_rotates_to_icrs_and_applies_transmittance():
    camera = FisheyeCamera(24)
    directions, valid = camera.directions()
    grid = wavelength_grid(4)
    angle = 0.7  # a rotation about the x axis as "ICRS -> ENU"
    c, s = math.cos(angle), math.sin(angle)
    to_horizon = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    image = np.zeros((24, 24, 4))
    add_star_background(image, valid, directions, to_horizon, grid,
                        transmittance_of=lambda rays: np.full((rays.shape[0], 4), 0.5),
                        magnitude_limit=7.0)
    expected = 0.5 * integrated_starlight_radiance(directions[valid] @ to_horizon, grid, 7.0)
    np.testing.assert_allclose(image[valid], expected, rtol=1e-12)
    assert np.all(image[~valid] == 0.0)
