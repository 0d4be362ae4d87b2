"""Colorimetry: CMF weights, XYZ, RGB spaces, adaptation, transfer curves, CCT."""

import colour
import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.spectrum.colour import (
    RGB_SPACES,
    cct_mccamy_1992,
    chromatic_adaptation,
    cmf_weights,
    decode_srgb_transfer,
    encode_srgb_transfer,
    luminance,
    rgb_to_xyz,
    spectral_to_xyz,
    white_balance,
    white_point_xyz,
    xy_chromaticity,
    xyz_to_rgb,
)
from skyscatter.spectrum.grid import cell_average, wavelength_grid

ONE_NM_GRID = wavelength_grid(470, 360.0, 830.0)
DEFAULT_GRID = wavelength_grid()
D65 = colour.SDS_ILLUMINANTS["D65"]  # CIE D65 relative SPD, 300–780 nm at 5 nm (colour-science)
ILLUMINANT_A = colour.SDS_ILLUMINANTS["A"]


def d65_on(grid):
    return cell_average(D65.wavelengths, D65.values, grid)


def neutral_error(rgb):
    return np.max(np.abs(rgb / np.mean(rgb) - 1.0))


@pytest.mark.parametrize("space", sorted(RGB_SPACES))
def test_d65_is_neutral_white_on_a_1_nm_grid(space):
    # The D65 SPD's own chromaticity (0.31273, 0.32903) differs from the rounded white point
    # (0.3127, 0.3290) used by the RGB spaces: that gives the measured 2.2e-4; tolerance 5e-4.
    rgb = xyz_to_rgb(spectral_to_xyz(d65_on(ONE_NM_GRID), ONE_NM_GRID), space)
    assert neutral_error(rgb) < 5e-4


@pytest.mark.parametrize("space", sorted(RGB_SPACES))
def test_d65_is_near_neutral_white_on_the_default_16_bin_grid(space):
    # 16 bins of 29.4 nm treat D65 as constant over each bin while x̄, ȳ, z̄ (integrated exactly)
    # vary strongly across it: the product is off by the covariance of the two within each bin.
    # Measured max |c/mean - 1|: 0.92 % (sRGB, blue), 0.65–0.82 % for the other spaces; point
    # samples of D65 at the bin centres instead of cell means give 2.9 %. Tolerance 1.2 %.
    rgb = xyz_to_rgb(spectral_to_xyz(d65_on(DEFAULT_GRID), DEFAULT_GRID), space)
    assert neutral_error(rgb) < 1.2e-2


def test_xyz_matches_colour_science_integration_on_a_1_nm_grid():
    # Another program: colour-science sd_to_XYZ (integration, k = 683.002) of D65 at 1 nm.
    # Our 1 nm cells are centred on half-nanometres and integrate the linear CMF interpolant,
    # colour sums point products: measured gap 2e-5 (Z), 3e-6 (X, Y); tolerance 1e-4.
    shape = colour.SpectralShape(360, 830, 1)
    reference = colour.sd_to_XYZ(D65.copy().align(shape, extrapolator_kwargs={"method": "Constant",
                                                                               "left": 0,
                                                                               "right": 0}),
                                 colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
                                 k=683.002, method="Integration")
    ours = spectral_to_xyz(d65_on(ONE_NM_GRID), ONE_NM_GRID)
    np.testing.assert_allclose(ours, reference, rtol=1e-4)


def test_cmf_weights_integrate_the_cmfs():
    # Identity: Σ_j W_j = K_m ∫ c̄ dλ over 360–830 nm for any grid covering the range (ȳ: 106.857,
    # the CIE 1 nm sum of the colour-science table). Our integral is the trapezoid of the table,
    # the reference its plain sum: they differ by half the end values, 3e-6 (z̄); tolerance 1e-5.
    reference = 683.002 * colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values.sum(0)
    for grid in (DEFAULT_GRID, ONE_NM_GRID):
        np.testing.assert_allclose(cmf_weights(grid).sum(0), reference, rtol=1e-5)


def test_cmf_weights_are_cached_and_read_only():
    assert cmf_weights(DEFAULT_GRID) is cmf_weights(list(DEFAULT_GRID))
    with pytest.raises(ValueError):
        cmf_weights(DEFAULT_GRID)[0, 0] = 1.0


def test_luminance_of_555_nm_is_683_lm_per_w():
    # Definition of K_m: 1 W m⁻² sr⁻¹ at 555 nm (ȳ = 1) is 683.002 cd m⁻². A 1 nm cell around
    # 555 nm carries 1 W m⁻² sr⁻¹; ȳ varies by ±0.0003 across it (tolerance 1e-4 relative).
    assert luminance([1.0], [555.0]) == pytest.approx(683.002, rel=1e-4)


@pytest.mark.parametrize("lead", [(), (5,), (2, 3)])
def test_shapes_of_the_array_functions(lead):
    spectral = np.ones(lead + (16,))
    xyz = spectral_to_xyz(spectral, DEFAULT_GRID)
    assert xyz.shape == lead + (3,)
    assert luminance(spectral, DEFAULT_GRID).shape == lead
    assert xyz_to_rgb(xyz).shape == lead + (3,)
    assert rgb_to_xyz(xyz).shape == lead + (3,)
    assert xy_chromaticity(xyz).shape == lead + (2,)
    assert cct_mccamy_1992(xy_chromaticity(xyz)).shape == lead
    assert chromatic_adaptation(xyz, xyz).shape == lead + (3,)
    assert white_balance(xyz, spectral, DEFAULT_GRID).shape == lead + (3,)
    assert encode_srgb_transfer(np.ones(lead)).shape == lead
    assert decode_srgb_transfer(np.ones(lead)).shape == lead


def test_black_is_finite():
    xyz = spectral_to_xyz(np.zeros(16), DEFAULT_GRID)
    np.testing.assert_array_equal(xyz, 0.0)
    np.testing.assert_allclose(xy_chromaticity(xyz), [0.3127, 0.3290])
    assert np.all(np.isfinite(xyz_to_rgb(xyz, "acescg")))


def test_float32_image_stays_float32():
    image = np.ones((4, 4, 16), dtype=np.float32)
    assert spectral_to_xyz(image, DEFAULT_GRID).dtype == np.float32


@pytest.mark.parametrize("space", sorted(RGB_SPACES))
def test_rgb_round_trip(space):
    xyz = np.random.default_rng(3).uniform(0.0, 2.0, (10, 3))
    np.testing.assert_allclose(rgb_to_xyz(xyz_to_rgb(xyz, space), space), xyz, rtol=1e-12,
                               atol=1e-12)


def test_srgb_matrix_matches_iec_61966_2_1():
    # IEC 61966-2-1 publishes the XYZ -> sRGB matrix to 4 decimals, got by inverting its own
    # rounded RGB -> XYZ matrix; ours is derived exactly from the primaries and D65
    # (0.3127, 0.3290). Measured gap 3.7e-4 (element [0, 0]); tolerance 5e-4.
    iec = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415],
                    [0.0557, -0.2040, 1.0570]])
    np.testing.assert_allclose(xyz_to_rgb(np.eye(3)).T, iec, atol=5e-4)


def test_acescg_matches_colour_science_with_bradford_from_d65():
    # Another program: colour.XYZ_to_RGB with D65 viewing white, Bradford adaptation to ACES.
    xyz = np.array([[0.2, 0.3, 0.4], [0.9505, 1.0, 1.089]])
    reference = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["ACEScg"],
                                  illuminant=np.array([0.3127, 0.3290]),
                                  chromatic_adaptation_transform="Bradford")
    np.testing.assert_allclose(xyz_to_rgb(xyz, "acescg"), reference, rtol=1e-6, atol=1e-9)


def test_adapting_illuminant_a_white_to_d65_gives_d65_white():
    # Von Kries identity: the source white maps onto the target white (at the source's Y).
    xyz_a = spectral_to_xyz(cell_average(ILLUMINANT_A.wavelengths, ILLUMINANT_A.values,
                                         ONE_NM_GRID), ONE_NM_GRID)
    adapted = chromatic_adaptation(xyz_a, xyz_a, "D65")
    np.testing.assert_allclose(adapted, white_point_xyz("D65") * xyz_a[1], rtol=1e-12)


def test_bradford_matches_colour_science_chromatic_adaptation():
    # Another program: colour.adaptation.chromatic_adaptation_VonKries, Bradford, A -> D65.
    wa = white_point_xyz("A")
    wd = white_point_xyz("D65")
    xyz = np.array([[0.3, 0.2, 0.1], [0.5, 0.5, 0.5]])
    reference = colour.adaptation.chromatic_adaptation_VonKries(xyz, wa, wd, transform="Bradford")
    np.testing.assert_allclose(chromatic_adaptation(xyz, wa, "d65"), reference, rtol=1e-10)


def test_white_balance_makes_the_light_neutral_in_srgb():
    # White balance to the light's own spectrum: a white surface lit by illuminant A ends up
    # R = G = B. Exact: our sRGB matrix is derived from the same D65 (0.3127, 0.3290) that
    # white_balance adapts to; tolerance 1e-6 for float rounding.
    light = cell_average(ILLUMINANT_A.wavelengths, ILLUMINANT_A.values, DEFAULT_GRID)
    xyz = spectral_to_xyz(light, DEFAULT_GRID)
    rgb = xyz_to_rgb(white_balance(xyz, light, DEFAULT_GRID))
    assert neutral_error(rgb) < 1e-6


def test_srgb_transfer_matches_iec_61966_2_1_points():
    # IEC 61966-2-1: encode(0.0031308) = 0.04045 (continuity point), encode(1) = 1,
    # encode(0.18) = 0.4614 (1.055·0.18^(1/2.4) − 0.055). Tolerance: rounding of the constants.
    np.testing.assert_allclose(encode_srgb_transfer([0.0, 0.0031308, 0.18, 1.0]),
                               [0.0, 0.04045, 0.46135, 1.0], atol=2e-5)
    x = np.linspace(-1.0, 2.0, 301)
    np.testing.assert_allclose(decode_srgb_transfer(encode_srgb_transfer(x)), x, atol=1e-12)
    np.testing.assert_allclose(encode_srgb_transfer(-x), -encode_srgb_transfer(x), atol=0.0)


def test_srgb_transfer_matches_colour_science():
    # Another program: colour-science's sRGB encoding CCTF (same IEC formula; float rounding).
    x = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(encode_srgb_transfer(x), colour.cctf_encoding(x, "sRGB"),
                               atol=1e-12)


def test_mccamy_cct_of_d65_is_6504_k():
    # CIE: D65 has CCT 6504 K; McCamy's cubic is within ±2 K of the exact value near 6500 K.
    assert cct_mccamy_1992([0.3127, 0.3290]) == pytest.approx(6504.0, abs=2.0)


def test_mccamy_cct_of_illuminant_a_is_2856_k():
    # CIE illuminant A: 2856 K, xy (0.44757, 0.40745) (CIE 015:2018); McCamy ±2 K.
    assert cct_mccamy_1992([0.44757, 0.40745]) == pytest.approx(2856.0, abs=2.0)


def test_unknown_colour_space_is_refused_naming_the_allowed_ones():
    with pytest.raises(InputError, match=r"unknown colour space 'adobe'; allowed: srgb, rec709, "
                                         r"display-p3, rec2020, acescg, aces2065-1"):
        xyz_to_rgb([0.5, 0.5, 0.5], "adobe")


def test_unknown_method_and_white_are_refused():
    with pytest.raises(InputError, match=r"unknown chromatic adaptation method 'cat99'"):
        chromatic_adaptation([0.5, 0.5, 0.5], [1.0, 1.0, 1.0], method="cat99")
    with pytest.raises(InputError, match=r"unknown white 'D66'"):
        chromatic_adaptation([0.5, 0.5, 0.5], [1.0, 1.0, 1.0], target_white="D66")
    with pytest.raises(InputError, match=r"a white must have Y > 0"):
        chromatic_adaptation([0.5, 0.5, 0.5], [1.0, 0.0, 1.0])


def test_spectrum_with_wrong_length_is_refused():
    with pytest.raises(InputError, match=r"16 grid wavelengths on its last axis; got shape \(15"):
        spectral_to_xyz(np.ones(15), DEFAULT_GRID)


def test_negative_wavelength_is_refused():
    with pytest.raises(InputError, match=r"wavelengths_nm must be positive and finite.*-1.0"):
        cmf_weights([-1.0, 500.0])


def test_shipped_colour_tables_equal_colour_science():
    # data/colour_cie.npz is a copy of colour-science's datasets (scripts/make_data/
    # colour_tables.py); the copy must be exact, and our normalised primary matrix (SMPTE RP
    # 177) must equal colour-science's for every shipped RGB space.
    from skyscatter.spectrum import colour as ours

    tables = ours._tables()
    cmfs = colour.colorimetry.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    np.testing.assert_array_equal(tables["cmf_xyz_bar"], np.asarray(cmfs.values).T)
    np.testing.assert_array_equal(tables["cmf_wavelengths_nm"], cmfs.wavelengths)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    np.testing.assert_array_equal(ours.illuminant_spectrum("D65", d65.wavelengths), d65.values)
    for name, primaries, white in zip(tables["rgb_names"], tables["rgb_primaries_xy"],
                                      tables["rgb_white_xy"], strict=True):
        space = colour.RGB_COLOURSPACES[ours.RGB_SPACES[str(name)]]
        np.testing.assert_array_equal(primaries, space.primaries)
        np.testing.assert_allclose(ours.normalised_primary_matrix(primaries, white),
                                   colour.models.normalised_primary_matrix(space.primaries,
                                                                           space.whitepoint),
                                   rtol=1e-12, atol=1e-15)
    for name, matrix in zip(tables["adaptation_names"], tables["adaptation_matrices"],
                            strict=True):
        expected = colour.adaptation.CHROMATIC_ADAPTATION_TRANSFORMS[
            ours.CHROMATIC_ADAPTATION_METHODS[str(name)]]
        np.testing.assert_array_equal(matrix, expected)
