"""Exposure, tone curves and sRGB encoding against their published formulas and known values."""

import math

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.render import tonemap as tm
from skyscatter.spectrum.colour import decode_srgb_transfer, encode_srgb_transfer

OPERATOR_NAMES = sorted(tm.OPERATORS)


def test_aces_narkowicz_known_values():
    # f(0) = 0; f(1) = 2.54 / 3.16 from the fitted coefficients; the limit 2.51/2.43 > 1 is clipped.
    assert tm.aces_narkowicz2016(0.0) == 0.0
    assert tm.aces_narkowicz2016(1.0) == pytest.approx(2.54 / 3.16, rel=1e-15)
    assert tm.aces_narkowicz2016(1e6) == 1.0
    assert 2.51 / 2.43 > 1.0


def test_exponential_at_one_is_one_minus_inverse_e():
    assert tm.exponential(1.0) == pytest.approx(1 - math.exp(-1), rel=1e-15)


def test_reinhard_and_clamp_known_values():
    np.testing.assert_allclose(tm.reinhard([0.0, 1.0, 3.0]), [0.0, 0.5, 0.75], rtol=1e-15)
    np.testing.assert_array_equal(tm.clamp([-1.0, 0.25, 7.0]), [0.0, 0.25, 1.0])


@pytest.mark.parametrize("name", OPERATOR_NAMES)
def test_operators_are_monotonic_and_map_into_unit_interval(name):
    x = np.concatenate([[0.0], np.logspace(-6, 6, 2001), [np.inf]])
    y = tm.tonemap(x, name)
    assert y[0] == 0.0 and y[-1] == 1.0
    assert np.all(np.diff(y) >= 0)
    assert np.all((y >= 0) & (y <= 1))


@pytest.mark.parametrize("name", OPERATOR_NAMES)
@pytest.mark.parametrize("shape", [(), (5,), (2, 3), (4, 5, 3)])
def test_tonemap_keeps_shape_and_clips_negative_input(name, shape):
    x = np.full(shape, -0.5)
    y = tm.tonemap(x, name)
    assert y.shape == shape and np.all(y == 0.0)


def test_tonemap_exposure_multiplies_before_the_curve():
    assert tm.tonemap(0.5, "exponential", exposure=2.0) == pytest.approx(1 - math.exp(-1))


def test_unknown_operator_names_the_choices():
    with pytest.raises(InputError, match="unknown tone-mapping operator 'filmic'; choose one of: "
                                         "aces, clamp, exponential, reinhard"):
        tm.tonemap(np.ones((2, 2, 3)), "filmic")


def test_exposure_scale_is_inverse_saturation_luminance_lagarde2014():
    # L_max = 1.2 · 2^EV100: at EV100 = 0 a luminance of 1.2 cd/m² just reaches 1.
    assert tm.exposure_scale(0.0) == pytest.approx(1 / 1.2, rel=1e-15)
    assert tm.exposure_scale(15.0) == pytest.approx(1 / (1.2 * 2**15), rel=1e-15)
    assert tm.exposure_scale(15.0, compensation_ev=1.0) == pytest.approx(2 / (1.2 * 2**15))


@pytest.mark.parametrize("luminance_cd_m2", [1e-4, 1.0, 5000.0])
def test_auto_exposure_puts_a_uniform_scene_at_the_meter_mid_value(luminance_cd_m2):
    # Meter K = 12.5 (ISO 2720), saturation 78/(q S), q = 0.65: mid value K q / 78 = 1/9.6.
    scene = np.full((8, 8), luminance_cd_m2)
    ev100 = tm.auto_ev100(scene)
    assert ev100 == pytest.approx(math.log2(luminance_cd_m2 * 100 / 12.5), abs=1e-12)
    assert luminance_cd_m2 * tm.exposure_scale(ev100) == pytest.approx(1 / 9.6, rel=1e-12)


def test_auto_exposure_uses_the_geometric_mean_of_valid_positive_pixels():
    scene = np.array([[1.0, 100.0], [0.0, 1e9]])
    valid = np.array([[True, True], [True, False]])  # the 1e9 pixel is outside the lens
    # geometric mean of 1 and 100 is 10 (the zero pixel is left out)
    assert tm.auto_ev100(scene, valid) == pytest.approx(math.log2(10 * 8), abs=1e-12)


def test_auto_exposure_of_a_black_scene_asks_for_an_explicit_ev():
    with pytest.raises(InputError, match="give an explicit EV100"):
        tm.auto_ev100(np.zeros((4, 4)))


def test_srgb_transfer_is_continuous_at_the_breakpoint_iec61966():
    below, above = encode_srgb_transfer(np.array([0.0031308, np.nextafter(0.0031308, 1)]))
    assert below == pytest.approx(12.92 * 0.0031308, rel=1e-15)
    # The two published branches meet to ~1e-7 at the rounded breakpoint.
    assert above == pytest.approx(below, abs=1e-7)


def test_srgb8_known_codes():
    # 50 % linear encodes to 0.7354 → 187.5 → 188, the standard 8-bit value; 1 → 255; 0 → 0.
    codes = tm.to_srgb8(np.array([0.0, 0.5, 1.0, 2.0, -1.0]))
    np.testing.assert_array_equal(codes, [0, 188, 255, 255, 0])
    assert codes.dtype == np.uint8


def test_srgb8_codes_are_the_rounded_transfer_function_iec61966():
    # Reference: round(255 V(L)) with the IEC 61966-2-1 encoding, value by value, over
    # random values in [0, 1] (dense near 0, where the codes are closest), values 1e-9
    # (relative) to either side of each code's midpoint (exactly at one, either code is a
    # rounding of the same number) and values out of range.
    rng = np.random.default_rng(7)
    midpoints = decode_srgb_transfer((np.arange(255) + 0.5) / 255.0)
    values = np.concatenate([rng.random(200_000) ** 4, midpoints * (1 - 1e-9),
                             midpoints * (1 + 1e-9), [-3.0, 0.0, 1.0, 7.0]])
    expected = np.rint(encode_srgb_transfer(np.clip(values, 0.0, 1.0)) * 255.0)
    np.testing.assert_array_equal(tm.to_srgb8(values), expected)


def test_srgb8_keeps_image_shape():
    assert tm.to_srgb8(np.zeros((3, 4, 3))).shape == (3, 4, 3)


def test_srgb8_refuses_nan():
    with pytest.raises(InputError, match="1 NaN values"):
        tm.to_srgb8(np.array([0.2, np.nan]))


def test_night_compensation_follows_the_krawczyk_key():
    # alpha(L) = 1.03 - 2 / (2 + log10(L + 1)) (Krawczyk et al. 2005), relative to L = 3000.
    def key(luminance):
        return 1.03 - 2.0 / (2.0 + math.log10(luminance + 1.0))

    assert tm.night_compensation_ev(3000.0) == pytest.approx(0.0, abs=1e-12)
    for luminance in (30.0, 300.0, 1e4):
        expected = math.log2(key(luminance) / key(3000.0))
        assert tm.night_compensation_ev(luminance) == pytest.approx(expected, rel=1e-12)
    # dark scenes: the metered grey 1/9.6 (K q / 78) goes to Krawczyk's dark-scene key 0.03
    for luminance in (1e-4, 0.05, 1.0):
        assert tm.night_compensation_ev(luminance) == pytest.approx(math.log2(0.03 * 9.6),
                                                                    rel=1e-12)
    # night is exposed darker than day, and the change is monotonic
    values = [tm.night_compensation_ev(x) for x in (1e-4, 1e-2, 1.0, 30.0, 100.0, 3000.0)]
    assert values == sorted(values) and values[0] < -1.7
    with pytest.raises(InputError):
        tm.night_compensation_ev(-1.0)


def test_night_adapted_exposure_meters_a_black_sky_with_stars_as_night():
    # A black sky with a few bright star pixels meters at the natural night sky's luminance
    # (Falchi et al. 2016), not at the stars'.
    sky = np.zeros((64, 64))
    sky[3, 5] = sky[40, 9] = 50.0
    ev100, night = tm.night_adapted_exposure(sky, np.ones_like(sky, dtype=bool))
    floor_ev = math.log2(tm.NATURAL_NIGHT_SKY_CD_M2 * 100.0 / tm.METER_CALIBRATION_K)
    assert ev100 == pytest.approx(floor_ev, abs=0.02)
    assert night == pytest.approx(tm.night_compensation_ev(tm.NATURAL_NIGHT_SKY_CD_M2), abs=0.01)
    # a bright uniform day sky is metered as before, with no night shift
    day = np.full((8, 8), 3000.0)
    ev_day, night_day = tm.night_adapted_exposure(day, np.ones_like(day, dtype=bool))
    assert ev_day == pytest.approx(tm.auto_ev100(day), abs=1e-12)
    assert night_day == pytest.approx(0.0, abs=1e-9)


def test_adapted_ev100_is_a_first_order_low_pass():
    # After one time constant a step is followed by 1 - 1/e of its size; with no history or
    # tau = 0 the meter is used as it is.
    assert tm.adapted_ev100(None, 5.0, 60.0, 600.0) == 5.0
    assert tm.adapted_ev100(10.0, 5.0, 60.0, 0.0) == 5.0
    assert tm.adapted_ev100(10.0, 0.0, 600.0, 600.0) == pytest.approx(10.0 * math.exp(-1.0))
    # two half steps equal one whole step (exponential smoothing composes)
    half = tm.adapted_ev100(tm.adapted_ev100(10.0, 0.0, 300.0, 600.0), 0.0, 300.0, 600.0)
    assert half == pytest.approx(tm.adapted_ev100(10.0, 0.0, 600.0, 600.0), rel=1e-12)
