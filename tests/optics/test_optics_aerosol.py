"""Ångström-law optics against Bruneton's 2017 demo constants and closed forms."""

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.aerosol import AngstromOptics, angstrom_law
from skyscatter.optics.phase import CornetteShanksPhase, RayleighPhase
from skyscatter.spectrum.tabulated import SpectralParameter


def test_angstrom_law_closed_form():
    # tau(lambda) = tau_0 (lambda / lambda_0)^-alpha: halving lambda multiplies by 2^alpha.
    assert angstrom_law(275.0, 0.1, 550.0, 1.3) == pytest.approx(0.1 * 2**1.3, rel=1e-14)
    assert angstrom_law(550.0, 0.1, 550.0, 1.3) == pytest.approx(0.1, rel=1e-15)


def test_bruneton_rayleigh_as_angstrom_optics():
    # Bruneton 2017 demo: beta_R = 1.24062e-6 lambda[µm]^-4 m^-1 -> 5.802e-6, 13.558e-6,
    # 33.1e-6 m^-1 at 680, 550, 440 nm (demo.cc kRayleigh); evaluated here by hand.
    optics = AngstromOptics(extinction_at_reference=1.24062e-6, reference_wavelength_nm=1000.0,
                            angstrom_exponent=4.0, phase=RayleighPhase())
    wl = np.array([680.0, 550.0, 440.0])
    expected = 1.24062e-6 * (wl * 1e-3) ** -4
    np.testing.assert_allclose(optics.extinction_per_density(wl), expected, rtol=1e-14)
    np.testing.assert_allclose(optics.scattering_per_density(wl), expected, rtol=1e-14)
    np.testing.assert_allclose(expected, [5.802e-6, 13.558e-6, 33.1e-6], rtol=1e-3)


def test_bruneton_mie_as_angstrom_optics():
    # Bruneton 2017 demo: alpha = 0, beta = 5.328e-3 over H = 1200 m -> 4.44e-6 m^-1
    # extinction, albedo 0.9 -> 3.996e-6 m^-1 scattering, at every wavelength.
    optics = AngstromOptics(extinction_at_reference=5.328e-3 / 1200.0, angstrom_exponent=0.0,
                            single_scattering_albedo=0.9, phase=CornetteShanksPhase(0.8))
    wl = np.array([360.0, 550.0, 830.0])
    np.testing.assert_allclose(optics.extinction_per_density(wl), 4.44e-6, rtol=1e-12)
    np.testing.assert_allclose(optics.scattering_per_density(wl), 3.996e-6, rtol=1e-12)


def test_spectral_albedo_multiplies_extinction():
    ssa = SpectralParameter.table([440.0, 680.0], [0.8, 0.9])
    optics = AngstromOptics(extinction_at_reference=1e-5, angstrom_exponent=1.0,
                            single_scattering_albedo=ssa, phase=RayleighPhase())
    wl = np.array([440.0, 560.0, 680.0])
    ratio = optics.scattering_per_density(wl) / optics.extinction_per_density(wl)
    np.testing.assert_allclose(ratio, [0.8, 0.85, 0.9], rtol=1e-14)


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_angstrom_shapes(shape):
    wl = np.full(shape, 500.0)
    optics = AngstromOptics(extinction_at_reference=1e-5, angstrom_exponent=1.0,
                            phase=RayleighPhase())
    assert angstrom_law(wl, 0.1, 550.0, 1.3).shape == shape
    assert optics.scattering_per_density(wl).shape == shape


def test_angstrom_finite_at_grid_edges():
    out = angstrom_law([1.0, 360.0, 830.0, 1e5], 0.1, 550.0, 2.0)
    assert np.all(np.isfinite(out)) and np.all(out > 0.0)


@pytest.mark.parametrize("kwargs, message", [
    ({"extinction_at_reference": -1.0}, "extinction_at_reference = -1.0 must be finite and >= 0"),
    ({"reference_wavelength_nm": 0.0}, "reference_wavelength_nm = 0.0 must be finite and > 0"),
    ({"single_scattering_albedo": 1.2}, r"single_scattering_albedo = \[1.2\] must lie in \[0, 1\]"),
    ({"angstrom_exponent": float("nan")}, "angstrom_exponent = nan must be finite"),
])
def test_bad_angstrom_arguments(kwargs, message):
    args = {"extinction_at_reference": 1e-5, "angstrom_exponent": 1.0, "phase": RayleighPhase()}
    args.update(kwargs)
    with pytest.raises(InputError, match=message):
        AngstromOptics(**args)
