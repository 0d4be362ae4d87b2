"""Rayleigh cross-sections and King factors against Bodhaine 1999 and colour-science."""

import colour.phenomena.rayleigh as colour_rayleigh
import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.phase import PenndorfPhase, RayleighPhase
from skyscatter.optics.rayleigh import (
    RayleighOptics,
    TabulatedScatteringOptics,
    king_factor_air_bodhaine_1999,
    king_factor_from_depolarization,
    rayleigh_cross_section,
    rayleigh_optical_depth_bodhaine1999,
)
from skyscatter.optics.refractive_index import gas_refractivity
from skyscatter.spectrum.tabulated import SpectralParameter

PERCENT = 1e-2  # cross-sections are ~1e-31 m^2: every approx below on them sets abs=0
# Bodhaine 1999's sea-level column of air for 1013.25 hPa at 45° latitude [molecules m^-2]
# (2.1544e25 cm^-2; Bodhaine et al. 1999).
COLUMN_45DEG_M2 = 2.1544e29


def test_rayleigh_depth_from_cross_section_matches_bodhaine_1999_eq30():
    # Ours: sigma_air(lambda) x Bodhaine's column; reference: Bodhaine 1999 eq. 30, a fit to the
    # same calculation. Tolerance 1 %: the fit's own error (< 0.1 % in the visible) plus the
    # column rounding; measured worst deviation is 0.12 %.
    wl = np.arange(400.0, 701.0, 50.0)
    tau = RayleighOptics().scattering_per_density(wl) * COLUMN_45DEG_M2
    np.testing.assert_allclose(tau, rayleigh_optical_depth_bodhaine1999(wl), rtol=1 * PERCENT)


def test_rayleigh_depth_matches_reference_data_table():
    # Bodhaine et al. 1999 eq. 30 evaluated at 400-700 nm, printed to 4 decimals; 0.6 % covers the
    # rounding (up to 0.14 % at 700 nm) and the 0.12 % gap between eq. 30 and first principles.
    wl = [400.0, 450.0, 500.0, 550.0, 650.0, 700.0]
    expected = [0.3602, 0.2211, 0.1434, 0.0971, 0.0492, 0.0364]
    tau = RayleighOptics().scattering_per_density(wl) * COLUMN_45DEG_M2
    np.testing.assert_allclose(tau, expected, rtol=0.6 * PERCENT)


def test_bodhaine_eq30_reproduces_its_published_values():
    # The fit itself against the table's values (4 decimals): rounding only.
    tau = rayleigh_optical_depth_bodhaine1999([400.0, 550.0, 700.0])
    np.testing.assert_allclose(tau, [0.3602, 0.0971, 0.0364], atol=6e-5)


def test_cross_section_matches_colour_science_bodhaine():
    # colour-science `scattering_cross_section(wl_cm, CO2, T=288.15)` implements Bodhaine 1999
    # from first principles (cm^2). Its molecular density comes from its own constants, which
    # differ from N_s = 2.546899e19 cm^-3 by < 0.01 %; tolerance 0.05 %.
    wl = np.arange(380.0, 781.0, 20.0)
    ours = RayleighOptics(co2_ppm=360.0).scattering_per_density(wl)
    theirs = colour_rayleigh.scattering_cross_section(wl * 1e-7, 360.0, 288.15) * 1e-4
    np.testing.assert_allclose(ours, theirs, rtol=0.05 * PERCENT)


def test_king_factor_of_air_matches_colour_science_and_hand_value():
    # Bodhaine eqs. 23-27 evaluated by hand at 550 nm, 360 ppm: 1.04882; colour-science
    # `F_air_Bodhaine1999` is an independent implementation (agreement to 1e-12).
    assert king_factor_air_bodhaine_1999(550.0, 360.0) == pytest.approx(1.04882, abs=1e-5)
    wl = np.arange(360.0, 831.0, 10.0)
    np.testing.assert_allclose(king_factor_air_bodhaine_1999(wl, 400.0),
                               colour_rayleigh.F_air_Bodhaine1999(wl * 1e-3, 400.0), rtol=1e-12)


def test_king_factor_from_young_1980_depolarization():
    # delta = 0.0279 (Young 1980; Costa 2020 Table 1) -> F = 1.0481 (Young's 1.048); 4 decimals.
    assert king_factor_from_depolarization(0.0279) == pytest.approx(1.0481, abs=5e-5)
    assert king_factor_from_depolarization(0.0) == 1.0


def test_cross_section_is_the_lorentz_lorenz_limit_of_costa_eq11():
    # Costa 2020 Eq. 11 writes 8 pi^3 (n^2-1)^2 / (3 N lambda^4) per molecule x N, i.e. (n^2+2)
    # replaced by 3: it agrees with Bodhaine eq. 2 to 2 (n^2-1)/3 ~ 0.04 %.
    wl = 550.0
    n_minus_1, n_s = gas_refractivity("air", wl)
    n2m1 = (1.0 + n_minus_1) ** 2 - 1.0
    costa = 8.0 * np.pi**3 * n2m1**2 / (3.0 * n_s**2 * (wl * 1e-9) ** 4)
    ours = rayleigh_cross_section(wl, n_minus_1, n_s, 1.0)
    assert ours == pytest.approx(costa, rel=0.05 * PERCENT, abs=0.0)


def test_cross_section_is_independent_of_reference_density():
    # (n^2-1)/N is a molecular property: scaling N and n-1 together leaves sigma unchanged to
    # first order (the (n^2+2) term changes by ~(n-1) ~ 3e-4).
    n_minus_1, n_s = gas_refractivity("air", 500.0)
    a = rayleigh_cross_section(500.0, n_minus_1, n_s, 1.0)
    b = rayleigh_cross_section(500.0, 0.5 * n_minus_1, 0.5 * n_s, 1.0)
    assert a == pytest.approx(b, rel=0.05 * PERCENT, abs=0.0)


def test_optics_extinction_equals_scattering_and_phase_by_name():
    optics = RayleighOptics(phase="penndorf")
    wl = np.array([440.0, 550.0, 680.0])
    np.testing.assert_array_equal(optics.extinction_per_density(wl),
                                  optics.scattering_per_density(wl))
    assert isinstance(optics.phase, PenndorfPhase)
    assert isinstance(RayleighOptics().phase, RayleighPhase)


def test_depolarization_overrides_king_model():
    # Bodhaine's F(550) = 1.0488, delta = 0.0279 gives 1.0481: ratio of cross-sections 0.9993.
    wl = np.array([550.0])
    a = RayleighOptics(depolarization=0.0279).scattering_per_density(wl)
    b = RayleighOptics().scattering_per_density(wl)
    assert a / b == pytest.approx(1.04806 / 1.04882, rel=1e-4)


@pytest.mark.parametrize("kwargs, message", [
    ({"gas": "neon"}, r"unknown gas 'neon'; allowed: air, ar, ch4, co2, h2, he, n2, o2"),
    ({"gas": "he"}, r"'bodhaine-1999' has no value for gas 'he'; it covers: air, ar, co2, n2, "
                    r"o2 \(or give depolarization=...\)"),
    ({"king": "bates"}, r"unknown king 'bates'; allowed: bodhaine-1999, none"),
    ({"phase": "mie"}, r"unknown phase 'mie'; allowed: penndorf, rayleigh"),
    ({"king": "none", "depolarization": 0.03}, "either king or depolarization"),
    ({"depolarization": 0.9}, r"must lie in \[0, 6/7\)"),
    ({"co2_ppm": -1.0}, "co2_ppm = -1.0 must be >= 0"),
])
def test_bad_rayleigh_arguments_name_the_allowed_values(kwargs, message):
    with pytest.raises(InputError, match=message):
        RayleighOptics(**kwargs)


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_rayleigh_functions_keep_the_input_shape(shape):
    wl = np.full(shape, 500.0)
    n_minus_1, n_s = gas_refractivity("air", wl)
    assert rayleigh_cross_section(wl, n_minus_1, n_s, king_factor_air_bodhaine_1999(wl)).shape \
        == shape
    assert rayleigh_optical_depth_bodhaine1999(wl).shape == shape
    assert RayleighOptics().scattering_per_density(wl).shape == shape
    assert RayleighOptics(depolarization=0.03).king_factor(wl).shape == shape


def test_rayleigh_finite_at_grid_edges():
    wl = np.array([200.0, 360.0, 830.0, 2000.0])
    for optics in (RayleighOptics(), RayleighOptics(gas="co2", king="none")):
        sigma = optics.scattering_per_density(wl)
        assert np.all(np.isfinite(sigma)) and np.all(sigma > 0.0)


def test_tabulated_scattering_returns_costa_2020_coefficients():
    # Costa 2020 Table 1: Earth Rayleigh beta = (5.1768, 12.2588, 30.5964) e-6 m^-1 at
    # (680, 550, 440) nm, returned exactly at the table wavelengths.
    beta = SpectralParameter.table([680.0, 550.0, 440.0], [5.1768e-6, 12.2588e-6, 30.5964e-6])
    optics = TabulatedScatteringOptics(scattering=beta, phase=RayleighPhase())
    wl = np.array([440.0, 550.0, 680.0])
    np.testing.assert_allclose(optics.scattering_per_density(wl),
                               [30.5964e-6, 12.2588e-6, 5.1768e-6], rtol=1e-15)
    np.testing.assert_array_equal(optics.extinction_per_density(wl),
                                  optics.scattering_per_density(wl))
    with_ext = TabulatedScatteringOptics(scattering=4e-5, extinction=4e-6, phase=RayleighPhase())
    assert with_ext.extinction_per_density(wl).tolist() == [4e-6] * 3


def test_tabulated_scattering_rejects_negative_values_and_missing_phase():
    with pytest.raises(InputError, match="scattering = \\[-1.0\\] must be finite and >= 0"):
        TabulatedScatteringOptics(scattering=SpectralParameter.constant(-1.0),
                                  phase=RayleighPhase())
    with pytest.raises(InputError, match="needs a phase function"):
        TabulatedScatteringOptics(scattering=SpectralParameter.constant(1e-6))
