"""The Mars validation cases: their geometry and curve helpers against closed forms, the
transmittance against Beer-Lambert, the skipping of missing presets, and one quick case run."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import Constituent
from skyscatter.atmosphere.profiles import ExponentialProfile
from skyscatter.optics.rayleigh import TabulatedScatteringOptics
from skyscatter.validate import mars_mer_transmittance
from skyscatter.validate.mars_blue_aureole import GlowProfile
from skyscatter.validate.mars_mer_colour import MEASURED_MEAN, ColourTrack, best_fit_optical_depth
from skyscatter.validate.mars_mer_transmittance import direct_transmittance
from skyscatter.validate.mars_models import (
    almucantar_azimuth_deg,
    angle_from_sun_deg,
    dust_factor_for_transmittance,
    dust_optical_depth,
    dust_scaled,
    framework_reading,
    half_radius_deg,
    load_models,
    orders_for,
    sky_direction,
)
from skyscatter.validate.report import ValidationSettings

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
SCALE_HEIGHT_M = 11_100.0
EXTINCTION_PER_M = 4.0e-5  # tau = 0.444: a dusty-season Mars


@pytest.fixture(scope="module")
def costa():
    return load_atmosphere("mars-costa")


@pytest.fixture(scope="module")
def absorber(costa):
    """Mars geometry with one pure absorber, extinction k exp(-h/H), no scattering."""
    optics = TabulatedScatteringOptics(scattering=0.0, extinction=EXTINCTION_PER_M)
    layer = Constituent("dust", ExponentialProfile(SCALE_HEIGHT_M), optics)
    return replace(costa, constituents=(layer,), name="absorber")


def _absorber_tau(atmosphere) -> float:
    # closed form: k H (1 - exp(-top / H))
    return EXTINCTION_PER_M * SCALE_HEIGHT_M * (1.0 - math.exp(-atmosphere.top_altitude_m
                                                               / SCALE_HEIGHT_M))


def test_zenith_transmittance_of_an_exponential_absorber_is_exp_minus_tau(absorber):
    # Ray marched (1024 trapezoids over 120 km) on the profile's 2001 levels: the relative
    # error of tau is ~(dz/H)^2/12 < 1e-5, hence 1e-5 on T (measured: 2.6e-6).
    t = direct_transmittance(absorber, 880.0, 90.0)
    assert float(t) == pytest.approx(math.exp(-_absorber_tau(absorber)), rel=1e-5)
    assert dust_optical_depth(absorber, 880.0) == pytest.approx(_absorber_tau(absorber),
                                                                rel=1e-5)


@pytest.mark.parametrize("elevation_deg", [30.0, 45.0, 60.0, 75.0])
def test_slant_transmittance_is_beer_lambert_with_the_first_curvature_term(absorber,
                                                                           elevation_deg):
    # Air mass of an exponential shell to first order in H/R (expanding the altitude along the
    # path, h = s mu + s^2 sin^2 / 2R): m = sec(z) (1 - tan^2(z) H / R). The next term is
    # ~3 (tan^2 z H/R)^2 = 2.9e-4 of m at 30 deg elevation (measured: 3.7e-4 there, 2e-5 at
    # 60 deg); limit on ln T: 1e-3 relative.
    zenith = math.radians(90.0 - elevation_deg)
    mass = (1.0 - math.tan(zenith) ** 2 * SCALE_HEIGHT_M / absorber.bottom_radius_m) \
        / math.cos(zenith)
    t = float(direct_transmittance(absorber, 880.0, elevation_deg))
    assert -math.log(t) == pytest.approx(_absorber_tau(absorber) * mass, rel=1e-3)
    # and plain exp(-tau / mu) is within the curvature term (1 % at 30 deg)
    assert t == pytest.approx(math.exp(-_absorber_tau(absorber) / math.cos(zenith)), rel=1e-2)


def test_direct_transmittance_shapes(absorber):
    assert direct_transmittance(absorber, 880.0, 45.0).shape == ()
    assert direct_transmittance(absorber, 880.0, np.linspace(5, 90, 5)).shape == (5,)
    values = direct_transmittance(absorber, 880.0, np.full((2, 3), 0.5))
    assert values.shape == (2, 3) and np.all(np.isfinite(values)) and np.all(values > 0)


def test_dust_factor_for_a_transmittance_reproduces_it_at_the_zenith(costa):
    # closed form f = (-ln T - tau_other) / tau_dust against the ray-marched zenith value
    tau_dust = dust_optical_depth(costa, 880.0)
    tau_total = -math.log(float(direct_transmittance(costa, 880.0, 90.0)))
    for target in (0.5, 0.05):
        f = float(dust_factor_for_transmittance(target, tau_total - tau_dust, tau_dust))
        assert float(direct_transmittance(dust_scaled(costa, f), 880.0, 90.0)) == \
            pytest.approx(target, rel=1e-4)
    assert dust_factor_for_transmittance([0.9, 0.1], 0.0, 1.0).shape == (2,)


def test_dust_scaled_scales_the_optical_depth_and_raises_the_orders(costa):
    dusty = dust_scaled(costa, 5.0)
    assert dust_optical_depth(dusty, 550.0) == pytest.approx(5 * dust_optical_depth(costa, 550.0))
    # docs/physics/orders.md: 6 orders for mars-costa (tau 0.20), 13 for 5 times its dust
    assert orders_for(costa) == 6
    assert dusty.scattering_orders == 13 and "dust x5" in dusty.name
    assert dust_scaled(costa, 1.0) is costa


def test_angle_from_sun_matches_the_dot_product_of_the_directions():
    rng = np.random.default_rng(4)
    ev, av, es, az = rng.uniform(-10, 90, 50), rng.uniform(0, 360, 50), rng.uniform(-5, 90, 50), \
        rng.uniform(0, 360, 50)
    dots = np.sum(sky_direction(ev, av) * sky_direction(es, az), axis=-1)
    np.testing.assert_allclose(np.cos(np.radians(angle_from_sun_deg(ev, av, es, az))), dots,
                               atol=1e-12)
    assert angle_from_sun_deg(10.0, 0.0, 10.0).shape == ()
    assert angle_from_sun_deg(np.zeros((2, 3)), 5.0, 2.0).shape == (2, 3)
    assert float(angle_from_sun_deg(90.0, 123.0, 0.0)) == pytest.approx(90.0)


@pytest.mark.parametrize("elevation_deg", [0.0, 2.0, 14.0, 40.0])
def test_almucantar_azimuth_gives_the_asked_angle_from_the_sun(elevation_deg):
    gamma = np.array([0.0, 0.5, 3.0, 30.0, 90.0, 180.0 - 2.0 * elevation_deg])
    azimuth = almucantar_azimuth_deg(gamma, elevation_deg)
    np.testing.assert_allclose(angle_from_sun_deg(elevation_deg, azimuth, elevation_deg), gamma,
                               atol=1e-6)
    assert azimuth[-1] == pytest.approx(180.0)
    with pytest.raises(ValueError, match="not on the almucantar"):
        almucantar_azimuth_deg(181.0 - 2.0 * elevation_deg, elevation_deg)


def test_half_radius_of_an_exponential_glow_matches_its_closed_form():
    # x(g) = a - b exp(-g / g0): halfway between x(3) and x(30) at
    # g = -g0 ln((exp(-3/g0) + exp(-30/g0)) / 2); 0.05 deg sampling, linear interpolation.
    g0 = 8.0
    angles = np.arange(2.0, 120.0, 0.05)
    x = 0.38 - 0.1 * np.exp(-angles / g0)
    expected = -g0 * math.log(0.5 * (math.exp(-3.0 / g0) + math.exp(-30.0 / g0)))
    assert half_radius_deg(angles, x, 3.0, 30.0) == pytest.approx(expected, abs=0.01)
    # a falling curve works the same way; on a piecewise-linear curve the result is exact
    assert half_radius_deg(angles, -x, 3.0, 30.0) == pytest.approx(expected, abs=0.01)
    assert half_radius_deg([3.0, 10.0, 30.0], [0.0, 1.0, 2.0], 3.0, 30.0) == pytest.approx(10.0)
    assert half_radius_deg([3.0, 13.0, 30.0], [0.0, 0.25, 1.0], 3.0, 30.0) == \
        pytest.approx(13.0 + 17.0 / 3.0)


def test_half_radius_is_nan_without_a_glow():
    angles = np.linspace(1.0, 60.0, 30)
    assert math.isnan(half_radius_deg(angles, np.full(30, 0.3), 3.0, 30.0))


def test_glow_profile_metrics_on_a_synthetic_curve():
    angles = np.array([2.0, 3.0, 10.0, 30.0, 90.0])
    xy = np.column_stack([[0.25, 0.26, 0.30, 0.34, 0.36], [0.30, 0.31, 0.33, 0.35, 0.36]])
    p = GlowProfile("test", "almucantar", angles, xy)
    assert p.delta_x == pytest.approx(0.08) and p.delta_y == pytest.approx(0.04)
    assert p.half_radius_deg == pytest.approx(10.0)
    assert p.cct_k.shape == (5,) and p.cct_k[0] > p.cct_k[-1]  # bluer near the sun


def test_missing_presets_are_skipped_with_a_note():
    models = load_models(("mars-costa", "mars-no-such-model"))
    assert models.names == ["mars-costa"]
    assert "mars-no-such-model" in models.missing
    assert models.notes() == ["mars-no-such-model skipped: no such preset yet "
                              "(src/skyscatter/atmosphere/presets/)."]


def test_framework_reading_reverses_collienne_gas_coefficients():
    collienne = load_atmosphere("mars-collienne")
    variant = framework_reading(collienne)
    gas = lambda atm, wl: atm.optical_profile([wl], monochromatic=True).scattering_per_density[0]  # noqa: E731
    assert float(gas(collienne, 440.0)[0]) == pytest.approx(5.75e-6)
    assert float(gas(variant, 440.0)[0]) == pytest.approx(19.918e-6)
    assert float(gas(variant, 680.0)[0]) == pytest.approx(5.75e-6)
    assert framework_reading(load_atmosphere("mars-costa"), "no-such-constituent") is None


def test_measured_mer_mean_is_the_thesis_mean():
    # Meyran 2022 §5.1.2 (Bell et al. 2006): the mean of the four datasets, 0.402, 0.381
    np.testing.assert_allclose(MEASURED_MEAN, (0.402, 0.381), atol=5e-4)


def test_best_fit_optical_depth_interpolates_in_log_tau():
    # means linear in u = log10(tau / 0.1): x = 0.30 + 0.10 u, y = 0.33 + 0.06 u; the target
    # (0.38, 0.378) is met exactly at u = 0.8, tau = 0.1 * 10^0.8 = 0.631 (2001-point search)
    def track(tau, x, y):
        xy = np.tile([x, y], (3, 1))
        return ColourTrack("t", "mars-hybrid", 1.0, tau, np.array([30.0, 60.0, 90.0]), xy)

    tau, distance = best_fit_optical_depth([track(1.0, 0.40, 0.39), track(0.1, 0.30, 0.33)],
                                           (0.38, 0.378))
    assert tau == pytest.approx(0.1 * 10**0.8, rel=2e-3)
    assert distance < 1e-4
    assert track(1.0, 0.40, 0.39).distance((0.38, 0.378)) == pytest.approx(0.02)


def test_quick_transmittance_case_runs_writes_its_figure_and_passes(tmp_path):
    result = mars_mer_transmittance.run(ValidationSettings(output_dir=tmp_path, quick=True,
                                                           log=lambda line: None))
    assert result.passed and result.checks
    assert (tmp_path / result.figures[0].path).read_bytes()[:8] == PNG_SIGNATURE
    zenith = result.metrics["zenith_transmittance"]
    assert zenith["Costa"] == pytest.approx(0.827, abs=0.001)  # exp(-0.190)
    json.dumps(result.metrics)  # the summary must be able to hold them
