"""Forward-peak truncation (`transport.phase_truncation`) against closed forms: the clipped
share of a Henyey-Greenstein phase function from its analytic cumulative integral, Rayleigh
scattering left alone, and the normalisation kept."""

import numpy as np
import pytest

from skyscatter.optics.phase import henyey_greenstein, rayleigh
from skyscatter.transport.phase_truncation import MIN_PEAK_FRACTION, truncate_forward_peak

N_ANGLE = 4097  # the tables' sampling (TableResolution.phase_angles)
THETA = np.linspace(0.0, np.pi, N_ANGLE)


def sampled(function) -> np.ndarray:
    return function(np.cos(THETA))[None, :, None]


def hg_clipped_share(g: float, angle_deg: float) -> float:
    """int_{theta < theta_c} (p - p(theta_c)) d omega for HG: the integral of p over the cap is
    (1 - g^2) / (2 g) (1 / (1 - g) - 1 / sqrt(1 + g^2 - 2 g mu_c)) (the HG cumulative
    distribution), and p(theta_c) times the cap's solid angle 2 pi (1 - mu_c)."""
    mu_c = np.cos(np.radians(angle_deg))
    cap = (1.0 - g * g) / (2.0 * g) * (1.0 / (1.0 - g)
                                       - 1.0 / np.sqrt(1.0 + g * g - 2.0 * g * mu_c))
    edge = henyey_greenstein(mu_c, g)
    return float(cap - edge * 2.0 * np.pi * (1.0 - mu_c))


@pytest.mark.parametrize("g, angle_deg", [(0.65, 10.0), (0.85, 5.0), (0.95, 10.0), (0.95, 2.0)])
def test_clipped_share_of_henyey_greenstein_matches_its_closed_form(g, angle_deg):
    _, fraction = truncate_forward_peak(sampled(lambda nu: henyey_greenstein(nu, g)), angle_deg)
    # the clip holds p at the first sample at or beyond the angle
    edge_deg = np.degrees(THETA[np.count_nonzero(np.radians(angle_deg) > THETA)])
    # trapezoid rule on 0.044 deg samples: the peak of g = 0.95 is 3 deg wide, resolved to 1e-4
    assert fraction[0, 0] == pytest.approx(hg_clipped_share(g, edge_deg), abs=1e-4)


def test_smooth_part_keeps_the_normalisation_and_the_wide_angles():
    phase = sampled(lambda nu: henyey_greenstein(nu, 0.9))
    smooth, fraction = truncate_forward_peak(phase, 10.0)
    weight = 2.0 * np.pi * np.sin(THETA)
    assert np.trapezoid(smooth[0, :, 0] * weight, THETA) == pytest.approx(
        np.trapezoid(phase[0, :, 0] * weight, THETA), rel=1e-12)
    outside = np.radians(10.0) <= THETA
    # beyond the clip p* = p / (1 - f): the peak's share moved into the delta function
    np.testing.assert_allclose(smooth[0, outside, 0] * (1.0 - fraction[0, 0]),
                               phase[0, outside, 0], rtol=1e-12)
    assert np.all(np.diff(smooth[0, ~outside, 0]) == 0.0)  # flat inside the clip


def test_rayleigh_and_a_zero_angle_are_left_alone():
    phase = np.concatenate([sampled(rayleigh), sampled(lambda nu: henyey_greenstein(nu, 0.7))])
    smooth, fraction = truncate_forward_peak(phase, 10.0)
    assert fraction[0, 0] == 0.0 and np.array_equal(smooth[0], phase[0])
    assert fraction[1, 0] > MIN_PEAK_FRACTION
    smooth, fraction = truncate_forward_peak(phase, 0.0)
    assert np.all(fraction == 0.0) and np.array_equal(smooth, phase)


def test_a_stricter_minimum_leaves_a_broad_lobe_alone_and_clips_a_peak():
    # the tables' `TABLE_MIN_PEAK_FRACTION` (5 %): at 15 deg Henyey-Greenstein g 0.65 (Earth's
    # aerosol) loses 3.7 % (closed form), g 0.9 loses more and is clipped as without the minimum
    phase = np.concatenate([sampled(lambda nu: henyey_greenstein(nu, 0.65)),
                            sampled(lambda nu: henyey_greenstein(nu, 0.9))])
    edge_deg = np.degrees(THETA[np.count_nonzero(np.radians(15.0) > THETA)])
    assert hg_clipped_share(0.65, edge_deg) < 0.05 < hg_clipped_share(0.9, edge_deg)
    smooth, fraction = truncate_forward_peak(phase, 15.0, min_fraction=0.05)
    assert fraction[0, 0] == 0.0 and np.array_equal(smooth[0], phase[0])
    assert fraction[1, 0] == truncate_forward_peak(phase[1:], 15.0)[1][0, 0]
