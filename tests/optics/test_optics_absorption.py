"""Ozone cross-section and AbsorberOptics against published optical depths and the source file."""

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.absorption import (
    DOBSON_UNIT_M2,
    AbsorberOptics,
    ozone_cross_section,
)
from skyscatter.spectrum.tabulated import SpectralParameter

PERCENT = 1e-2  # cross-sections are ~1e-25 m^2: every approx below on them sets abs=0


def test_dobson_unit_is_a_0p01mm_layer_at_stp():
    # 1 DU = 1e-5 m x Loschmidt 2.6867811e25 m^-3 (CODATA 2018); commonly rounded to 2.687e20.
    assert abs(DOBSON_UNIT_M2 / 2.687e20 - 1.0) < 1e-4


def test_ozone_optical_depth_300du_at_600nm_matches_serdyuchenko():
    # Serdyuchenko et al. 2014, 233 K, 10-nm bin mean (Bruneton 2017 demo.cc): 5.019e-25 m^2 ->
    # tau = 0.0405 for 300 DU. Ours is Malicet/Brion at 295 K averaged over 1 nm: 5.144e-25 m^2
    # -> 0.0415.
    # Tolerance 5 %: Chappuis-band temperature dependence and dataset differences of a few %.
    tau = ozone_cross_section(600.0) * 300.0 * DOBSON_UNIT_M2
    assert tau == pytest.approx(0.040, rel=5 * PERCENT)


def test_ozone_cross_section_matches_source_point_values():
    # Ecosystem probe of musica's O3_1.nc (0.01-nm points): sigma(600) = 5.15e-21 cm^2,
    # sigma(254) = 1.13e-17 cm^2. A 0.1-nm cell around the point smooths the 0.01-nm structure:
    # 1 % covers it (the Hartley peak and Chappuis maximum are smooth on 0.1 nm).
    for wl, sigma_cm2 in ((600.0, 5.15e-21), (254.0, 1.13e-17)):
        got = ozone_cross_section(wl, single_cell_width_nm=0.1)
        assert got == pytest.approx(sigma_cm2 * 1e-4, rel=1 * PERCENT, abs=0.0)


def test_ozone_10nm_band_means_track_serdyuchenko_233k():
    # Bruneton's demo table (IUP Bremen / Serdyuchenko 233 K, "10-nm bin averages";
    # demo.cc). Its value at lambda matches our mean over [lambda, lambda + 10] nm
    # (centred bins differ by up to 17 %, so that is evidently its binning). Measured gap
    # 1.4-5.7 %; tolerance 7 %: Chappuis-band temperature dependence (233 vs 295 K) and the
    # Brion vs Serdyuchenko datasets differ by a few percent, most in the band wings.
    reference = {500.0: 1.48e-25, 550.0: 3.5e-25, 590.0: 4.701e-25, 600.0: 5.019e-25,
                 610.0: 4.305e-25, 650.0: 2.238e-25, 700.0: 7.455e-26}
    for lam, ref in reference.items():
        ours = ozone_cross_section(lam + 5.0, single_cell_width_nm=10.0)
        assert ours == pytest.approx(ref, rel=7 * PERCENT, abs=0.0), lam


def test_cell_average_of_neighbouring_cells_is_the_mean_over_their_union():
    # Identity of cell averages: two adjacent 1-nm cells average to the 2-nm cell.
    a, b = ozone_cross_section([599.5, 600.5])
    both = ozone_cross_section(600.0, single_cell_width_nm=2.0)
    assert 0.5 * (a + b) == pytest.approx(both, rel=1e-9, abs=0.0)


def test_ozone_zero_outside_data_and_partial_cells_use_covered_part():
    # Data cover 195-830 nm: wholly outside -> 0; the 830-nm cell of a 10-nm grid averages
    # 825-830 nm only.
    sigma = ozone_cross_section([820.0, 830.0, 840.0])
    assert sigma[2] == 0.0 and sigma[1] > 0.0
    assert ozone_cross_section(150.0) == 0.0
    covered = ozone_cross_section(827.5, single_cell_width_nm=5.0)
    assert sigma[1] == pytest.approx(covered, rel=1e-9, abs=0.0)


@pytest.mark.parametrize("shape", [(), (1,), (5,)])
def test_ozone_cross_section_shapes(shape):
    # Grids are 1-D and ascending everywhere in skyscatter (spectrum.grid.cell_edges).
    wl = 500.0 if shape == () else np.linspace(450.0, 650.0, shape[-1])
    out = ozone_cross_section(wl)
    assert out.shape == shape and np.all(np.isfinite(out)) and np.all(out > 0.0)


def test_ozone_cross_section_finite_at_edges():
    out = ozone_cross_section([195.0, 195.05, 829.95, 830.0])
    assert np.all(np.isfinite(out)) and np.all(out > 0.0)


def test_non_monotonic_grid_is_an_input_error():
    with pytest.raises(InputError, match="ascending"):
        ozone_cross_section([500.0, 600.0, 550.0])
    with pytest.raises(InputError, match="must be finite and > 0 nm"):
        ozone_cross_section([-1.0, 500.0])


def test_absorber_optics_is_a_pure_absorber():
    optics = AbsorberOptics()
    wl = np.array([500.0, 600.0, 700.0])
    np.testing.assert_array_equal(optics.extinction_per_density(wl), ozone_cross_section(wl))
    np.testing.assert_array_equal(optics.scattering_per_density(wl), 0.0)
    assert optics.phase is None
    table = AbsorberOptics(SpectralParameter.table([500.0, 700.0], [1e-25, 3e-25]))
    np.testing.assert_allclose(table.extinction_per_density(wl), [1e-25, 2e-25, 3e-25])


def test_unknown_cross_section_lists_known_names():
    with pytest.raises(InputError,
                       match=r"unknown cross-section 'o3-bogus'; known: o3-malicet-brion"):
        AbsorberOptics("o3-bogus")
    with pytest.raises(InputError, match="must be finite and >= 0"):
        AbsorberOptics(SpectralParameter.constant(-1e-25))
