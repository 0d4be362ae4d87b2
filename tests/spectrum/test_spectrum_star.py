"""Planck radiance, solar limb darkening and the Star light source (skyscatter.spectrum.star)."""

import math

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.spectrum.grid import cell_widths, wavelength_grid
from skyscatter.spectrum.solar import solar_irradiance_1au
from skyscatter.spectrum.star import (
    AU_M,
    SOLAR_RADIUS_M,
    Star,
    limb_darkening_disk_mean,
    limb_darkening_neckel_labs_1994,
    planck_spectral_radiance,
)

DEG = math.pi / 180.0
WIEN_B = 2.897771955e-3  # m K, Wien displacement constant (CODATA 2018)
STEFAN_BOLTZMANN = 5.670374419e-8  # W m⁻² K⁻⁴ (CODATA 2018)

# Neckel & Labs (1994), Solar Phys. 153, 91: measured 5th-degree limb-darkening polynomials
# a_0..a_5 at single wavelengths [nm] (their table, as transcribed in the ISP-SST/sstred pipeline,
# red_neckel_coefficients.pro). Independent of the analytic λ-fit we implement.
NECKEL_LABS_1994_TABLE = {
    303.327: [0.08011, 0.70695, 0.49910, -0.31080, -0.02177, 0.04642],
    349.947: [0.11012, 1.02168, -0.10924, -0.00055, -0.08688, 0.06487],
    401.970: [0.12323, 1.08648, -0.43974, 0.45912, -0.32759, 0.09850],
    559.950: [0.26892, 1.34319, -1.58427, 1.91271, -1.31350, 0.37295],
    700.875: [0.37885, 1.25553, -1.70908, 2.19647, -1.59554, 0.47378],
    1098.95: [0.51149, 1.19354, -2.00174, 2.66936, -1.94981, 0.57715],
}


# --- Planck -------------------------------------------------------------------------------------

@pytest.mark.parametrize("temperature_k", [3000.0, 5772.0, 10000.0])
def test_planck_peak_obeys_wien_displacement(temperature_k):
    # Wien: λ_max T = b. Grid step 0.01 nm -> peak located to ±0.005 nm (1e-5 relative at 500 nm).
    wl = np.arange(100.0, 2000.0, 0.01)
    peak_nm = wl[np.argmax(planck_spectral_radiance(wl, temperature_k))]
    assert peak_nm * 1e-9 * temperature_k == pytest.approx(WIEN_B, rel=2e-5)


@pytest.mark.parametrize("temperature_k", [300.0, 5772.0, 20000.0])
def test_planck_integrates_to_stefan_boltzmann(temperature_k):
    # π ∫ B_λ dλ = σ T⁴. Log grid 10 nm – 10 mm, trapezoid in ln λ; truncation < 1e-6 of total,
    # quadrature error < 1e-6: tolerance 1e-5.
    wl = np.geomspace(10.0, 1e7, 200_001)
    b = planck_spectral_radiance(wl, temperature_k)
    total = math.pi * np.trapezoid(b * wl, np.log(wl))
    assert total == pytest.approx(STEFAN_BOLTZMANN * temperature_k**4, rel=1e-5)


def test_planck_matches_rayleigh_jeans_at_long_wavelengths():
    # Closed form: B_λ -> 2 c k T / λ⁴ when hc/(λkT) << 1 (λ = 1 m, T = 5772 K: x = 2.5e-6).
    c, k = 299_792_458.0, 1.380649e-23
    wl_m = 1.0
    expected = 2.0 * c * k * 5772.0 / wl_m**4 * 1e-9
    assert planck_spectral_radiance(1e9, 5772.0) == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize(("wl_shape", "t_shape"), [((), ()), ((5,), ()), ((16,), (2, 3)),
                                                   ((2, 3), (4,))])
def test_planck_shape_is_temperature_shape_plus_wavelength_shape(wl_shape, t_shape):
    wl = np.full(wl_shape, 550.0)
    t = np.full(t_shape, 5772.0)
    b = planck_spectral_radiance(wl, t)
    assert b.shape == t_shape + wl_shape
    assert np.all(np.isfinite(b))


def test_planck_is_finite_at_extremes():
    b = planck_spectral_radiance([1.0, 1e9], [10.0, 1e6])
    assert np.all(np.isfinite(b)) and np.all(b >= 0.0)


def test_planck_refuses_bad_temperature():
    with pytest.raises(InputError, match=r"temperature_k must be positive and finite; got -1.0"):
        planck_spectral_radiance(550.0, -1.0)


# --- limb darkening -----------------------------------------------------------------------------

@pytest.mark.parametrize("wavelength_nm", sorted(NECKEL_LABS_1994_TABLE))
def test_limb_darkening_matches_neckel_labs_1994_measured_polynomials(wavelength_nm):
    # Ours: Neckel's analytic λ-fits; reference: the measured polynomial at that wavelength.
    # Largest gap measured 0.0095 (limb, μ = 0, at 560 nm; 0.0015–0.0072 at the other five
    # wavelengths); tolerance 0.012 in I(μ)/I(1).
    mu = np.linspace(0.0, 1.0, 21)
    expected = np.polyval(NECKEL_LABS_1994_TABLE[wavelength_nm][::-1], mu)
    ours = limb_darkening_neckel_labs_1994(mu, wavelength_nm)
    np.testing.assert_allclose(ours, expected, atol=0.012)


def test_limb_darkening_is_one_at_disk_centre_and_darker_towards_the_limb():
    grid = np.concatenate([np.linspace(250.0, 4000.0, 300), [372.98, 385.0, 422.57, 1100.0]])
    grid.sort()
    np.testing.assert_allclose(limb_darkening_neckel_labs_1994(1.0, grid), 1.0, atol=1e-12)
    mu = np.linspace(0.0, 1.0, 101)
    ld = limb_darkening_neckel_labs_1994(mu, grid)  # (101, n_wl)
    assert np.all(ld > 0.0)
    assert np.all(np.diff(ld, axis=0) > 0.0)


def test_limb_darkening_at_550_nm_limb_ratio():
    # Neckel & Labs (1994) measured polynomial at 559.95 nm: I(0.1)/I(1) = 0.3892. Tolerance
    # 0.015: the 10 nm offset moves it by ~0.008, the analytic fit by up to 0.005 (measured 0.389).
    value = limb_darkening_neckel_labs_1994(0.1, 550.0)
    assert value == pytest.approx(0.3892, abs=0.015)


def test_disk_mean_is_the_integral_of_the_law():
    # Σ 2 a_k/(k + 2) against numerical ∫ I(μ) 2μ dμ (trapezoid, 2001 points: error ~1e-7).
    mu = np.linspace(0.0, 1.0, 2001)
    for wl in (320.0, 400.0, 550.0, 900.0):
        numeric = np.trapezoid(limb_darkening_neckel_labs_1994(mu, wl) * 2 * mu, mu)
        assert limb_darkening_disk_mean(wl) == pytest.approx(numeric, abs=1e-6)


@pytest.mark.parametrize(("mu_shape", "wl_shape"), [((), ()), ((5,), (16,)), ((2, 3), (16,))])
def test_limb_darkening_shape(mu_shape, wl_shape):
    ld = limb_darkening_neckel_labs_1994(np.full(mu_shape, 0.5), np.full(wl_shape, 500.0))
    assert ld.shape == mu_shape + wl_shape


@pytest.mark.parametrize("mu", [-0.1, 1.5, np.nan])
def test_limb_darkening_refuses_mu_outside_0_1(mu):
    with pytest.raises(InputError, match=r"cos_limb must lie in \[0, 1\]"):
        limb_darkening_neckel_labs_1994(mu, 550.0)


# --- Star ---------------------------------------------------------------------------------------

def test_sun_angular_radius_at_earth_and_mars():
    # asin(6.957e8 m / 1 AU) = 0.26645° (IAU 2015 B3 radius, IAU 2012 AU); Mars at 1.524 AU:
    # 0.17484°. Tolerance 0.001° (the brief's; the closed form agrees to 1e-6°).
    assert Star.sun().angular_radius_rad / DEG == pytest.approx(0.2666, abs=1e-3)
    assert Star.sun(1.524).angular_radius_rad / DEG == pytest.approx(0.175, abs=1e-3)


def test_blackbody_sun_total_irradiance_is_the_nominal_solar_constant():
    # IAU 2015 B3: S = 1361 W m⁻², T_eff = 5772 K, R = 6.957e8 m at 1 AU (σT⁴(R/AU)² = 1361.2).
    # T_eff is rounded to 1 K: ±0.5 K -> ±0.47 W m⁻²; grid 50 nm–100 µm misses < 0.01 W m⁻².
    star = Star.blackbody("bb-sun", 5772.0, SOLAR_RADIUS_M, AU_M)
    grid = wavelength_grid(20_000, 50.0, 100_050.0)
    total = np.sum(star.irradiance_toa(grid) * cell_widths(grid))
    assert total == pytest.approx(1361.0, abs=0.6)


def test_sun_irradiance_follows_the_inverse_square_law():
    grid = wavelength_grid()
    np.testing.assert_allclose(Star.sun().irradiance_toa(grid), solar_irradiance_1au(grid))
    np.testing.assert_allclose(Star.sun(1.524).irradiance_toa(grid),
                               solar_irradiance_1au(grid) / 1.524**2, rtol=1e-12)


@pytest.mark.parametrize("star", [Star.sun(), Star.sun(1.524),
                                  Star.blackbody("M dwarf", 3200.0, 0.2 * SOLAR_RADIUS_M,
                                                 0.05 * AU_M)])
@pytest.mark.parametrize("limb_darkening", [True, False])
def test_disk_radiance_integrates_over_the_disk_to_the_irradiance(star, limb_darkening):
    # E = ∫_disk I cos θ dΩ = 2π ∫_0^α I(μ(θ)) cos θ sin θ dθ with sin θ = sin α √(1 - μ²).
    # Quadrature in θ (not in μ), substituting θ = α (1 - s²) to resolve the limb; trapezoid in
    # s: measured error 2.5e-7 at 2001 points, 6e-8 at 4001 (second order); tolerance 1e-6.
    from dataclasses import replace
    star = replace(star, limb_darkening=limb_darkening)
    grid = wavelength_grid()
    alpha = star.angular_radius_rad
    s = np.linspace(0.0, 1.0, 4001)
    theta = alpha * (1.0 - s * s)
    dtheta_ds = 2.0 * alpha * s
    mu = np.sqrt(np.clip(1.0 - (np.sin(theta) / math.sin(alpha)) ** 2, 0.0, 1.0))
    radiance = star.disk_radiance(grid, mu)  # (4001, 16)
    integrand = radiance * (2 * np.pi * np.cos(theta) * np.sin(theta) * dtheta_ds)[:, None]
    irradiance = np.trapezoid(integrand, s, axis=0)
    np.testing.assert_allclose(irradiance, star.irradiance_toa(grid), rtol=1e-6)


def test_uniform_blackbody_disk_radiance_is_planck():
    # With no limb darkening the disk radiance is B_λ(T), averaged over the cell: for 1 nm cells
    # the mean differs from B at the centre by (w²/24) B''/B, measured <= 1.7e-6; tolerance 5e-6.
    star = Star("bb", "blackbody", 5772.0, SOLAR_RADIUS_M, AU_M, limb_darkening=False)
    grid = wavelength_grid(470, 360.0, 830.0)
    np.testing.assert_allclose(star.disk_radiance(grid, 0.3),
                               planck_spectral_radiance(grid, 5772.0), rtol=5e-6)


@pytest.mark.parametrize("mu_shape", [(), (5,), (2, 3)])
def test_disk_radiance_shape_and_finite_edges(mu_shape):
    mu = np.zeros(mu_shape)  # the limb
    radiance = Star.sun().disk_radiance(wavelength_grid(), mu)
    assert radiance.shape == mu_shape + (16,)
    assert np.all(np.isfinite(radiance)) and np.all(radiance > 0.0)


def test_star_refuses_unknown_spectrum_naming_the_allowed_ones():
    with pytest.raises(InputError, match=r"spectrum 'kurucz'; allowed: astm-g173, blackbody"):
        Star("x", "kurucz", 5772.0, SOLAR_RADIUS_M, AU_M)


def test_star_refuses_observer_inside_the_star():
    with pytest.raises(InputError, match=r"distance_m = 1.0 must exceed radius_m"):
        Star.blackbody("x", 5772.0, 2.0, 1.0)


def test_star_refuses_negative_radius_and_distance_au():
    with pytest.raises(InputError, match=r"radius_m = -1.0 must be a finite number > 0"):
        Star.blackbody("x", 5772.0, -1.0, AU_M)
    with pytest.raises(InputError, match=r"distance_au = 0 must be a finite number > 0"):
        Star.sun(0)


def test_star_refuses_negative_wavelength():
    with pytest.raises(InputError, match=r"wavelengths_nm must be positive and finite.*-400.0"):
        Star.sun().irradiance_toa([-400.0, 500.0])
