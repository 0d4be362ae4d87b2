"""Refractivity of air and CO2 against published values and colour-science."""

import colour.phenomena.rayleigh as colour_rayleigh
import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.refractive_index import (
    AIR_NUMBER_DENSITY_288K_M3,
    LOSCHMIDT_M3,
    gas_refractivity,
    refractivity_air_bodhaine_1999,
    refractivity_air_peck_reeder_1972,
    refractivity_ar_peck_fisher_1964,
    refractivity_ch4_kaye_laby,
    refractivity_co2_bideau_mehu_1973,
    refractivity_h2_peck_huang_1977,
    refractivity_he_mansfield_peck_1969,
    refractivity_n2_peck_khanna_1966,
    refractivity_o2_zhang_2008,
)

WAVELENGTHS_NM = np.arange(360.0, 831.0, 10.0)


def test_peck_reeder_matches_colour_science_implementation():
    # colour-science 0.4.x `air_refraction_index_Peck1972` (wavelength in µm) is an independent
    # implementation of the same formula; agreement to 1e-12 in n - 1 is rounding only.
    ours = refractivity_air_peck_reeder_1972(WAVELENGTHS_NM)
    theirs = colour_rayleigh.air_refraction_index_Peck1972(WAVELENGTHS_NM * 1e-3) - 1.0
    np.testing.assert_allclose(ours, theirs, rtol=1e-9)


def test_bodhaine_co2_correction_matches_colour_science():
    # colour-science `air_refraction_index_Bodhaine1999(wl_um, CO2_ppm)`; same formula, 1e-9.
    for co2_ppm in (300.0, 360.0, 420.0):
        ours = refractivity_air_bodhaine_1999(WAVELENGTHS_NM, co2_ppm)
        theirs = colour_rayleigh.air_refraction_index_Bodhaine1999(WAVELENGTHS_NM * 1e-3,
                                                                  co2_ppm) - 1.0
        np.testing.assert_allclose(ours, theirs, rtol=1e-9)


def test_air_refractivity_at_550nm_is_2p7782e_4():
    # Peck & Reeder at 15 °C: n - 1 = 2.7782e-4 at 550 nm (evaluated by hand from their
    # formula; Costa 2020 Table 1 prints m(550) = 1.00027783). Tolerance: last printed digit.
    assert refractivity_air_peck_reeder_1972(550.0) == pytest.approx(2.7782e-4, abs=1e-8)


def test_air_refractivity_matches_costa_2020_table_1_at_680_and_550nm():
    # Costa 2020 Table 1 (advanced mode) m(lambda) = 1.00027598 (680 nm), 1.00027783 (550 nm).
    # 1.5e-8 in n: half a unit in the 8th decimal plus the 300/360 ppm CO2 choice (5e-10 ... 1e-8).
    n = 1.0 + refractivity_air_bodhaine_1999([680.0, 550.0], co2_ppm=360.0)
    np.testing.assert_allclose(n, [1.00027598, 1.00027783], rtol=0, atol=1.5e-8)


def test_co2_refractivity_matches_costa_2020_table_1():
    # Costa 2020 Table 1: n_CO2 = (1.00044661, 1.00045019, 1.00045558) at (680, 550, 440) nm,
    # from Bideau-Mehu 1973 at 273 K. 680/550 nm: to the last printed digit (5e-9). At 440 nm the
    # formula gives 1.00045588: the printed value is 0.07 % of n - 1 lower (probably a
    # transposed digit), so that point gets 4e-7.
    n = 1.0 + refractivity_co2_bideau_mehu_1973([680.0, 550.0, 440.0])
    np.testing.assert_allclose(n[:2], [1.00044661, 1.00045019], rtol=0, atol=5e-9)
    assert n[2] == pytest.approx(1.00045558, abs=4e-7)


def test_gas_refractivity_returns_reference_number_density():
    # Bodhaine 1999: N_s = 2.546899e19 cm^-3 for 288.15 K; CODATA 2018 Loschmidt constant.
    _, n_air = gas_refractivity("air", 550.0)
    _, n_co2 = gas_refractivity("CO2", 550.0)
    assert n_air == AIR_NUMBER_DENSITY_288K_M3 == pytest.approx(2.546899e25, rel=1e-12)
    assert n_co2 == LOSCHMIDT_M3 == pytest.approx(2.6867811e25, rel=1e-12)


def test_unknown_gas_lists_known_gases():
    with pytest.raises(InputError, match=r"unknown gas 'xe'.*air, ar, ch4, co2, h2, he, n2, o2"):
        gas_refractivity("xe", 550.0)


@pytest.mark.parametrize("bad", [0.0, -550.0, np.nan])
def test_non_positive_wavelength_is_an_input_error(bad):
    with pytest.raises(InputError, match="must be finite and > 0 nm"):
        refractivity_air_peck_reeder_1972([550.0, bad])


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
@pytest.mark.parametrize("gas", ["air", "ar", "ch4", "co2", "h2", "he", "n2", "o2"])
def test_refractivity_keeps_the_input_shape(shape, gas):
    wl = np.full(shape, 550.0)
    n_minus_1, _ = gas_refractivity(gas, wl)
    assert n_minus_1.shape == shape


def test_refractivity_finite_at_the_ends_of_the_visible_and_beyond():
    # Poles of the dispersion formulas lie at 87 nm (air) and 4.1 µm (CO2): far outside.
    for gas in ("air", "co2"):
        n_minus_1, _ = gas_refractivity(gas, [200.0, 360.0, 830.0, 1690.0])
        assert np.all(np.isfinite(n_minus_1)) and np.all(n_minus_1 > 2e-4)


@pytest.mark.parametrize(("gas", "low"), [("n2", 2.7e-4), ("o2", 2.4e-4), ("ar", 2.6e-4),
                                          ("h2", 1.3e-4), ("he", 3.4e-5), ("ch4", 4e-4)])
def test_new_gases_finite_and_positive_from_200_to_1700_nm(gas, low):
    # Nearest poles: N2 83 nm, O2 115 nm, Ar 83 nm, H2 74 nm, He 49 nm; CH4 has none.
    n_minus_1, n_s = gas_refractivity(gas, [200.0, 360.0, 550.0, 830.0, 1690.0])
    assert np.all(np.isfinite(n_minus_1)) and np.all(n_minus_1 > low) and n_s > 2.5e25


# --- the pure gases of the [gas] table: each formula against an independent measurement ----

def _to_0c(n_minus_1, temperature_k):
    """n - 1 at 0 °C and the same pressure: proportional to the ideal-gas density."""
    return n_minus_1 * temperature_k / 273.15


@pytest.mark.parametrize(("function", "temperature_k", "kaye_laby_1e6"), [
    (refractivity_n2_peck_khanna_1966, 288.15, 298.0),
    (refractivity_o2_zhang_2008, 293.15, 271.0),
    (refractivity_co2_bideau_mehu_1973, 273.15, 449.0),
])
def test_refractivity_at_589nm_matches_kaye_laby_table(function, temperature_k, kaye_laby_1e6):
    # Kaye & Laby, Tables of Physical and Chemical Constants (NPL), 2.5.7: (n - 1) 1e6 at
    # 589.3 nm, 0 °C, 101325 Pa, printed to 3 digits. Ours scaled to 0 °C as an ideal gas.
    # Tolerance 0.4 %: the printed rounding (0.2 %) + the gases' non-ideality (0.1 %).
    ours = _to_0c(function(589.3), temperature_k)
    assert ours == pytest.approx(kaye_laby_1e6 * 1e-6, rel=0.4e-2)


WL_VISIBLE_NM = np.arange(470.0, 701.0, 10.0)


def test_o2_zhang_2008_matches_bates_1984_within_0p5_percent():
    # Bates (1984) O2 at 0 °C and 1013.25 hPa, (n - 1) 1e8 = A + B / (40.9 - sigma^2), with
    # (A, B) = (20564.8, 248089.9) for 288-546 nm and (21351.1, 218567.0) above, as implemented
    # in SASKTRAN2 (`_o2_refrac_bates`): older measurements. The measured gap grows from
    # +0.06 % at 470 nm to -0.34 % at 700 nm (the two dispersions differ); tolerance 0.5 %.
    s2 = (1e3 / WL_VISIBLE_NM) ** 2
    bates = 1e-8 * np.where(WL_VISIBLE_NM <= 546.0, 20564.8 + 248089.9 / (40.9 - s2),
                            21351.1 + 218567.0 / (40.9 - s2))
    ours = _to_0c(refractivity_o2_zhang_2008(WL_VISIBLE_NM), 293.15)
    np.testing.assert_allclose(ours, bates, rtol=0.5e-2)


def test_ar_peck_fisher_1964_matches_bates_1984_within_0p3_percent():
    # Bates (1984) Ar at 0 °C: n^2 - 1 = 5.547e-4 (1 + 5.15e-3 lam^-2 + 4.19e-5 lam^-4), lam µm,
    # as implemented in SASKTRAN2 (`_ar_refrac_bates`; after Dalgarno & Kingston 1960).
    lam = WL_VISIBLE_NM * 1e-3
    bates = np.sqrt(1.0 + 5.547e-4 * (1 + 5.15e-3 / lam**2 + 4.19e-5 / lam**4)) - 1.0
    ours = _to_0c(refractivity_ar_peck_fisher_1964(WL_VISIBLE_NM), 288.15)
    np.testing.assert_allclose(ours, bates, rtol=0.3e-2)


def test_h2_peck_huang_1977_matches_the_allen_form_within_0p3_percent():
    # n - 1 = 13.58e-5 (1 + 7.52e-3 lam^-2) (lam µm, 0 °C), the form quoted from Allen's
    # Astrophysical Quantities by Malik et al. (2017), AJ 153, 56, eq. 17 (HELIOS).
    lam = WL_VISIBLE_NM * 1e-3
    np.testing.assert_allclose(refractivity_h2_peck_huang_1977(WL_VISIBLE_NM),
                               13.58e-5 * (1 + 7.52e-3 / lam**2), rtol=0.3e-2)


def test_he_mansfield_peck_1969_long_wavelength_limit_is_the_static_polarisability():
    # He static polarisability volume 0.204956 Å^3 (CRC Handbook, "Atomic and molecular
    # polarizabilities"); dilute gas: n - 1 = 2 pi N alpha'. The formula's lambda -> infinity
    # limit 0.01470091 / 423.98 is 0.2 % above it; tolerance 0.5 %.
    static = 2 * np.pi * LOSCHMIDT_M3 * 0.204956e-30
    assert refractivity_he_mansfield_peck_1969(1e9) == pytest.approx(static, rel=0.5e-2)


def test_ch4_value_is_consistent_with_its_static_polarisability():
    # CH4 static polarisability volume 2.593 Å^3 (CRC Handbook): 2 pi N alpha' = 4.377e-4 at
    # 0 °C; n - 1 at 589.3 nm must lie above it by the dispersion (1.4 %; N2's is 1.3 % from
    # 0 to 589 nm): 0 ... 3 %.
    static = 2 * np.pi * LOSCHMIDT_M3 * 2.593e-30
    ratio = refractivity_ch4_kaye_laby(589.3) / static
    assert 1.0 < ratio < 1.03


def test_n2_branches_meet_at_468nm():
    # Sneep & Ubachs 2005: the Peck & Khanna and Bates branches join at 21360 cm^-1; their gap
    # there is 1.5e-4 of n - 1.
    wl = 1e7 / 21360.0
    below, above = refractivity_n2_peck_khanna_1966([wl * (1 - 1e-9), wl * (1 + 1e-9)])
    assert below == pytest.approx(above, rel=2e-4)
