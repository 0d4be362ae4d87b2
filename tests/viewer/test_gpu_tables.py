"""The viewer's table message: layout, colour conversion and float16 scaling against the
spectral tables it is made from, and physical checks on what it carries."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.spectrum.colour import spectral_to_xyz
from skyscatter.viewer.gpu_tables import FLOAT16_TARGET, decode, encode, gpu_tables
from skyscatter.viewer.table_service import TableService

# float16 keeps 11 significant bits: relative rounding 2^-11 of each scaled value
FLOAT16_RELATIVE = 2.0**-11


@pytest.fixture(scope="module")
def earth_preview():
    service = TableService()
    atmosphere, profile, tables = service.spectral_tables(
        service.parse({"atmosphere": "earth", "quality": "preview"}))
    return atmosphere, profile, tables, gpu_tables(tables, profile, atmosphere.planet.star)


def test_encode_decode_round_trip(earth_preview):
    gpu = earth_preview[3]
    back = decode(encode(gpu))
    assert back.header == gpu.header
    for name, array in gpu.arrays.items():
        np.testing.assert_array_equal(back.arrays[name], array)


def test_scattering_cells_are_the_xyz_of_the_spectral_cells(earth_preview):
    _, profile, tables, gpu = earth_preview
    n_r, n_mu, n_mu_s, n_nu, n_t, _ = tables.scattering.shape
    rng = np.random.default_rng(3)
    for _ in range(200):
        r, mu, s, nu, t = (int(rng.integers(n)) for n in (n_r, n_mu, n_mu_s, n_nu, n_t))
        expected = spectral_to_xyz(tables.scattering[r, mu, s, nu, t].astype(np.float64),
                                   profile.wavelengths_nm)
        scale = gpu.header["scales"]["scattering"][t]
        got = gpu.arrays["scattering"][t, r, mu, nu, s].astype(np.float64) * scale
        # float16 rounding of the value, plus the subnormal floor below 6.1e-5 of the scale
        np.testing.assert_allclose(got, expected, rtol=FLOAT16_RELATIVE,
                                   atol=6.1e-5 * scale)


def test_irradiance_is_exact_and_transmittance_stays_in_unit_range(earth_preview):
    _, profile, tables, gpu = earth_preview
    irradiance = gpu.arrays["irradiance"].astype(np.float64) * gpu.header["scales"]["irradiance"]
    expected = spectral_to_xyz(tables.irradiance, profile.wavelengths_nm)
    np.testing.assert_allclose(irradiance, expected, rtol=FLOAT16_RELATIVE,
                               atol=expected.max() * 2.0**-24)
    transmittance = (gpu.arrays["transmittance"].astype(np.float64)
                     * gpu.header["scales"]["transmittance"])
    assert transmittance.min() >= 0.0 and transmittance.max() <= 1.0 + FLOAT16_RELATIVE
    # a path with no air (from the top of the atmosphere straight up, x_mu = 0) transmits all
    np.testing.assert_allclose(transmittance[-1, 0], 1.0, atol=2 * FLOAT16_RELATIVE)
    assert np.max(np.abs(gpu.arrays["scattering"].astype(np.float64))) <= FLOAT16_TARGET


def test_sun_disk_integrates_to_the_sun_irradiance(earth_preview):
    """2 pi int_0^alpha L(theta) sin(theta) cos(theta) d theta = E (Star.disk_radiance's
    normalisation), with the 33 samples over cos(limb angle) interpolated linearly: within
    0.5 % (the linear interpolation of the limb-darkening curve)."""
    atmosphere, profile, _, gpu = earth_preview
    disk = np.array(gpu.header["sun_disk_xyz"])
    alpha = gpu.header["sun_angular_radius_rad"]
    theta = np.linspace(0.0, alpha, 4001)
    cos_limb = np.sqrt(np.clip(1.0 - (np.sin(theta) / np.sin(alpha)) ** 2, 0.0, 1.0))
    samples = np.linspace(0.0, 1.0, disk.shape[0])
    radiance = np.stack([np.interp(cos_limb, samples, disk[:, c]) for c in range(3)], -1)
    integrand = radiance * (np.sin(theta) * np.cos(theta))[:, None]
    flux = 2.0 * np.pi * np.trapezoid(integrand, theta, axis=0)
    np.testing.assert_allclose(flux, gpu.header["sun_irradiance_xyz"], rtol=5e-3)


def test_effective_phase_functions_are_normalised(earth_preview):
    """Each channel's phase function is a positive mix of the spectral ones, so it integrates
    to 1 over the sphere: within 1 % (the trapezoid rule on 4097 angles across the aerosol's
    forward peak)."""
    _, _, tables, gpu = earth_preview
    rows = gpu.header["phase_rows"]
    n_angle = gpu.header["phase_angles"]
    phase = gpu.arrays["phase"].astype(np.float64).reshape(-1, rows * 1024, 3)
    theta = np.linspace(0.0, np.pi, n_angle)
    for s in range(len(tables.scattering_names)):
        values = phase[s, :n_angle] * gpu.header["scales"]["phase"]
        total = 2.0 * np.pi * np.trapezoid(values * np.sin(theta)[:, None], theta, axis=0)
        np.testing.assert_allclose(total, 1.0, rtol=1e-2)
