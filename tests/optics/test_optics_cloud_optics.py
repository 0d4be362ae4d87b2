"""Cloud particle optics per gram of water (`optics.cloud_optics`) against closed forms: the
mass normalisation of the Mie cross-sections and the geometric-optics limit for ice."""

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.cloud_optics import (
    ICE_ASYMMETRY,
    ICE_DENSITY_G_M3,
    WATER_DENSITY_G_M3,
    ice_cloud_optics,
    liquid_cloud_optics,
)
from skyscatter.optics.size_distribution import ModifiedGamma

WAVELENGTHS_NM = np.array([400.0, 550.0, 700.0])


def test_liquid_mass_extinction_is_three_q_over_four_rho_r_eff():
    # Reference: k_ext = 3 <Q_ext> / (4 rho_w r_eff) with <Q_ext> the cross-section-weighted
    # efficiency (Stephens 1978, eq. 7), and <Q_ext> = 2 + 1.9924 <x^(-2/3)> from the edge
    # term of large spheres (Nussenzveig & Wiscombe 1980; 2.07-2.11 here). Tolerance 0.5 %:
    # the edge term's O(x^(-4/3)) remainder (~0.2 %) plus the wavelength interpolation of the
    # 10 nm Mie grid.
    r_eff_m = 10e-6
    optics = liquid_cloud_optics(10.0, 0.1, WAVELENGTHS_NM)
    radii, weights = ModifiedGamma(r_eff_m, 0.1).quadrature(5000)
    area = weights * radii**2
    x = 2.0 * np.pi * radii[:, None] / (WAVELENGTHS_NM * 1e-9)
    q_ext = np.sum(area[:, None] * (2.0 + 1.9924 * x ** (-2.0 / 3.0)), axis=0) / area.sum()
    expected = 3.0 * q_ext / (4.0 * WATER_DENSITY_G_M3 * r_eff_m)
    np.testing.assert_allclose(optics.mass_extinction_m2_g, expected, rtol=5e-3)


def test_liquid_droplets_are_conservative_and_forward_scattering():
    # Water absorbs < 1e-5 of the light a 10 µm droplet intercepts in the visible (Segelstein
    # 1981); g = 0.85-0.87 (Hansen & Travis 1974). The phase table integrates to 1 over the
    # sphere (2 pi int p sin theta dtheta), checked on a fine grid of the tabulated function.
    optics = liquid_cloud_optics(10.0, 0.1, WAVELENGTHS_NM)
    assert np.all(optics.single_scattering_albedo > 1.0 - 1e-5)
    assert np.all((optics.asymmetry > 0.85) & (optics.asymmetry < 0.875))
    theta = np.pi * np.linspace(0.0, 1.0, 200_001) ** 2
    p = optics.phase.evaluate(np.cos(theta), WAVELENGTHS_NM)
    norm = np.trapezoid(2.0 * np.pi * p * np.sin(theta)[:, None], theta, axis=0)
    np.testing.assert_allclose(norm, 1.0, rtol=2e-3)


def test_ice_follows_the_geometric_optics_limit():
    # Reference: Q_ext = 2 for convex particles much larger than the wavelength, with
    # r_eff = 3 V / (4 A): k_ext = 3 / (2 rho_i r_eff) (Foot 1988; Grenfell & Warren 1999).
    optics = ice_cloud_optics(30.0, WAVELENGTHS_NM)
    np.testing.assert_allclose(optics.mass_extinction_m2_g,
                               3.0 / (2.0 * ICE_DENSITY_G_M3 * 30e-6), rtol=1e-12)
    np.testing.assert_array_equal(optics.single_scattering_albedo, 1.0)
    assert np.all(optics.asymmetry == ICE_ASYMMETRY)


@pytest.mark.parametrize("call", [lambda: liquid_cloud_optics(0.5, 0.1, WAVELENGTHS_NM),
                                  lambda: liquid_cloud_optics(60.0, 0.1, WAVELENGTHS_NM),
                                  lambda: ice_cloud_optics(float("nan"), WAVELENGTHS_NM)])
def test_radii_outside_the_valid_range_are_refused(call):
    with pytest.raises(InputError, match="effective_radius_um"):
        call()
