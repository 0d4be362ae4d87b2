"""Mie optics of particle populations against miepython, closed forms and Meyran 2022's numbers."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import pytest
from numpy.polynomial import legendre

from skyscatter.errors import InputError
from skyscatter.optics import mie
from skyscatter.optics.mie import (
    MIE_ANGLES_DEG,
    MieOptics,
    angular_functions,
    anomalous_diffraction_efficiencies,
    particle_optics,
)
from skyscatter.optics.particle_index import ComplexIndex, load_material, maxwell_garnett
from skyscatter.optics.phase import PhaseFunction, TabulatedPhase
from skyscatter.optics.size_distribution import ModifiedGamma, Monodisperse

os.environ.setdefault("MIEPYTHON_USE_JIT", "1")
miepython = pytest.importorskip("miepython")

THETA = np.deg2rad(MIE_ANGLES_DEG)
MU = np.cos(THETA)
PERCENT = 0.01
DUST = ModifiedGamma(1.6e-6, 0.2)  # Meyran 2022 §3.3.2: Tomasko's a = 1.6 µm, b = 0.2
RGB_NM = [440.0, 550.0, 680.0]


def dust_index() -> ComplexIndex:
    # Meyran 2022 §3.3.2 (after Ehlers et al. 2014): 3 % hematite (Maxwell Garnett) in 1.5 + 0i.
    return maxwell_garnett(1.5 + 0j, load_material("hematite"), 0.03)


def radius_for(x: float, wavelength_nm: float) -> float:
    return x * wavelength_nm * 1e-9 / (2.0 * np.pi)


def sphere_integral(phase: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """2 pi int p(theta) weight(theta) sin(theta) dtheta on MIE_ANGLES_DEG (trapezoid)."""
    return 2.0 * np.pi * np.trapezoid(phase * (weight * np.sin(THETA))[:, None], THETA, axis=0)


@dataclass(frozen=True)
class GammaSample:
    """Meyran 2022 App. A.2.2: radii drawn by numpy's gamma(3, 0.32 µm), equal weights."""

    seed: int

    def quadrature(self, n_radii: int):
        radii = np.sort(np.random.default_rng(self.seed).gamma(3.0, 0.32e-6, n_radii))
        return radii, np.full(n_radii, 1.0 / n_radii)


@pytest.mark.parametrize("m", [1.5 + 0.0j, 1.33 + 0.01j, 1.95 + 0.79j])
@pytest.mark.parametrize("x", [0.1, 1.0, 10.0, 50.0, 200.0])
@pytest.mark.parametrize("phase_average", ["scattering", "number"])
def test_single_sphere_matches_miepython_directly(m, x, phase_average):
    # Independent path: miepython's own S1/S2 sums (i_unpolarized, norm "one" = 1 over 4 pi sr)
    # and efficiencies_mx. Only a_n, b_n are shared; the sums and the averaging are ours.
    # Measured agreement 3e-11 (x = 200); 1e-8 leaves room for other BLAS builds.
    wavelength_nm = 500.0
    r = radius_for(x, wavelength_nm)
    table = particle_optics(Monodisperse(r), ComplexIndex.constant(m.real, m.imag),
                            [wavelength_nm], phase_average=phase_average, cache_directory=False)
    q_ext, q_sca, _, g = miepython.efficiencies_mx(m.conjugate(), x)
    np.testing.assert_allclose(table.phase[:, 0],
                               miepython.i_unpolarized(m.conjugate(), x, MU, norm="one"),
                               rtol=1e-8)
    assert table.extinction_cross_section_m2[0] == pytest.approx(np.pi * r * r * q_ext, rel=1e-8)
    assert table.scattering_cross_section_m2[0] == pytest.approx(np.pi * r * r * q_sca, rel=1e-8)
    assert table.asymmetry[0] == pytest.approx(g, rel=1e-8, abs=1e-12)


@pytest.mark.parametrize("phase_average", ["scattering", "number"])
def test_phase_integrates_to_one_and_asymmetry_is_its_mean_cosine(phase_average):
    # Trapezoid rule on MIE_ANGLES_DEG: measured errors <= 7e-6 for these population phase
    # functions (smooth; 0.02° steps over the forward peak); tolerance 2e-5.
    table = particle_optics(DUST, dust_index(), [360.0, 550.0, 830.0], n_radii=1000,
                            phase_average=phase_average, cache_directory=False)
    np.testing.assert_allclose(sphere_integral(table.phase, np.ones_like(THETA)), 1.0, atol=2e-5)
    np.testing.assert_allclose(sphere_integral(table.phase, np.cos(THETA)), table.asymmetry,
                               atol=2e-5)
    assert table.phase.shape == (MIE_ANGLES_DEG.size, 3)


@pytest.mark.parametrize("m", [1.5 + 0.0j, 1.5 + 0.1j, 1.95 + 0.79j])
def test_small_particles_scatter_like_rayleigh(m):
    # x -> 0: p -> 3/(16 pi)(1 + mu^2), Q_sca -> (8/3) x^4 |(m^2 - 1)/(m^2 + 2)|^2
    # (Bohren & Huffman 1983, eq. 5.8). The first Mie corrections are O(x^2) = 1e-4 at x = 0.01.
    x = 0.01
    r = radius_for(x, 500.0)
    table = particle_optics(Monodisperse(r), ComplexIndex.constant(m.real, m.imag), [500.0],
                            cache_directory=False)
    np.testing.assert_allclose(table.phase[:, 0], 3.0 / (16.0 * np.pi) * (1.0 + MU**2), rtol=2e-4)
    q_sca = table.scattering_cross_section_m2[0] / (np.pi * r * r)
    assert q_sca == pytest.approx(8.0 / 3.0 * x**4 * abs((m**2 - 1) / (m**2 + 2)) ** 2, rel=2e-4)
    assert abs(table.asymmetry[0]) < 1e-4


def test_angular_functions_are_legendre_derivatives():
    # pi_n = P_n'(mu), tau_n = mu P_n'(mu) - (1 - mu^2) P_n''(mu) (Bohren & Huffman eqs. 4.46-4.47
    # with P_n^1 = sin(theta) P_n'); numpy's Legendre series as the independent reference.
    mu = np.linspace(-1.0, 1.0, 41)
    pi, tau = angular_functions(mu, 30)
    for n in (1, 2, 5, 30):
        p_n = legendre.Legendre.basis(n)
        d1, d2 = p_n.deriv(1)(mu), p_n.deriv(2)(mu)
        np.testing.assert_allclose(pi[n - 1], d1, rtol=1e-11, atol=1e-11 * n * n)
        np.testing.assert_allclose(tau[n - 1], mu * d1 - (1 - mu**2) * d2, rtol=1e-11,
                                   atol=1e-11 * n**4)
    np.testing.assert_allclose(pi[:, -1], np.arange(1, 31) * np.arange(2, 32) / 2, rtol=1e-14)


def test_angle_grid_resolves_the_forward_peak():
    assert MIE_ANGLES_DEG[0] == 0.0 and MIE_ANGLES_DEG[-1] == 180.0
    steps = np.diff(MIE_ANGLES_DEG)
    assert np.all(steps > 0.0)
    # Forward peak ~ 1/x rad wide: >= 10 steps across it for x = 500 (0.115°).
    assert steps[MIE_ANGLES_DEG[:-1] < 2.0].max() <= np.degrees(1.0 / 500.0) / 5.0
    assert 500 <= MIE_ANGLES_DEG.size <= 1000


# ----- Anomalous diffraction ------------------------------------------------------------------

def ada_extinction_meyran_2022_eq_2_32(x, m):
    """Eq. 2.32 of Meyran 2022 (van de Hulst), as printed, with tan(beta) = k/(n - 1)."""
    rho = 2.0 * x * (m.real - 1.0)
    beta = np.arctan(m.imag / (m.real - 1.0))
    c = np.cos(beta) / rho
    e = np.exp(-rho * np.tan(beta))
    return (2.0 - 4.0 * e * c * np.sin(rho - beta) - 4.0 * e * c**2 * np.cos(rho - 2.0 * beta)
            + 4.0 * c**2 * np.cos(2.0 * beta))


@pytest.mark.parametrize("m", [1.05 + 0.0j, 1.05 + 0.01j, 1.5 + 0.0154j, 1.33 + 1e-4j])
def test_ada_extinction_equals_meyran_2022_eq_2_32(m):
    # The printed form cancels for small rho (Q_ext ~ rho^2 / 2): at x = 0.5, m = 1.05 it keeps
    # ~10 digits, hence rtol 1e-9.
    x = np.array([0.5, 3.0, 10.0, 100.0, 1000.0])
    q_ext, _ = anomalous_diffraction_efficiencies(x, m)
    np.testing.assert_allclose(q_ext, ada_extinction_meyran_2022_eq_2_32(x, m), rtol=1e-9)


def test_ada_extinction_approaches_mie_for_a_soft_sphere():
    # van de Hulst: ADA is the m -> 1, x -> infinity limit. For m = 1.05 it misses Mie's edge
    # (grazing-ray) term, which shrinks with x: measured 4.4, 3.7, 2.5, 1.0 % at x = 30 ... 1000.
    x = np.array([30.0, 100.0, 300.0, 1000.0])
    q_ext, q_abs = anomalous_diffraction_efficiencies(x, 1.05)
    q_mie = miepython.efficiencies_mx(np.full(x.size, 1.05 + 0j), x)[0]
    gap = np.abs(q_ext / q_mie - 1.0)
    assert np.all(gap < 5 * PERCENT) and np.all(np.diff(gap) < 0.0)
    np.testing.assert_array_equal(q_abs, 0.0)


def test_ada_limits():
    # Q_ext -> 2 (extinction paradox) for x -> infinity; Q_abs -> 1 for an opaque sphere;
    # Q_abs -> (8/3) x k (absorption by the volume, 4 x k / 3 of the cross-section x 2) for
    # small 4 x k; nothing for m = 1.
    q_ext, q_abs = anomalous_diffraction_efficiencies(1e6, 1.05 + 0.01j)
    assert q_ext == pytest.approx(2.0, abs=1e-6) and q_abs == pytest.approx(1.0, abs=1e-6)
    x, k = 0.5, 1e-4
    _, q_abs = anomalous_diffraction_efficiencies(x, 1.5 + 1j * k)
    assert q_abs == pytest.approx(8.0 / 3.0 * x * k, rel=1e-3)
    assert anomalous_diffraction_efficiencies([1e-3, 1.0], 1.0 + 0j)[0].tolist() == [0.0, 0.0]


def test_ada_method_keeps_the_mie_phase_function():
    index = ComplexIndex.constant(1.05, 0.001)
    r = radius_for(300.0, 500.0)
    kwargs = dict(wavelengths_nm=[500.0], cache_directory=False)
    ada = particle_optics(Monodisperse(r), index, method="ada", **kwargs)
    exact = particle_optics(Monodisperse(r), index, method="mie", **kwargs)
    np.testing.assert_array_equal(ada.phase, exact.phase)
    np.testing.assert_array_equal(ada.asymmetry, exact.asymmetry)
    q_ext, q_abs = anomalous_diffraction_efficiencies(300.0, 1.05 + 0.001j)
    assert ada.extinction_cross_section_m2[0] == pytest.approx(np.pi * r * r * q_ext, rel=1e-12)
    assert ada.scattering_cross_section_m2[0] == pytest.approx(np.pi * r * r * (q_ext - q_abs),
                                                               rel=1e-12)


# ----- the Mars dust of Meyran's thesis (2022, Hochschule Hannover) ---------------------------

def test_meyran_2022_reproduction_with_a_seeded_radius_sample():
    # The reference: the thesis's App. A.2 algorithm re-run with 5000 radii from
    # numpy.random.default_rng(1).gamma(3, 0.32 µm) and miepython 3.3.0 (it matches the thesis's
    # Table 4.1 albedos and shader table ends); with the same radii every printed number is
    # reproduced (tolerance: half a unit of the last digit).
    sample = GammaSample(seed=1)
    table = particle_optics(sample, dust_index(), RGB_NM, n_radii=5000, phase_average="number",
                            cache_directory=False)
    assert np.mean(sample.quadrature(5000)[0]) == pytest.approx(0.950e-6, abs=0.0005e-6)
    np.testing.assert_allclose(table.single_scattering_albedo, [0.667, 0.812, 0.956], atol=6e-4)
    np.testing.assert_allclose(table.extinction_cross_section_m2, [8.630e-12, 8.828e-12,
                                                                   9.078e-12], atol=0.5e-15)
    np.testing.assert_allclose(table.scattering_cross_section_m2, [5.757e-12, 7.166e-12,
                                                                   8.682e-12], atol=0.5e-15)
    np.testing.assert_allclose(table.phase[0], [17.07, 9.21, 5.31], atol=0.005)
    np.testing.assert_allclose(table.phase[-1], [0.0538, 0.0846, 0.1058], atol=0.00005)
    # The same re-run, C_sca-weighted: forward peak at 440 nm 40.7 sr^-1, back 0.027 sr^-1;
    # g = 0.854 / 0.787 / 0.725.
    weighted = particle_optics(sample, dust_index(), RGB_NM, n_radii=5000,
                               cache_directory=False)
    assert weighted.phase[0, 0] == pytest.approx(40.7, abs=0.05)
    assert weighted.phase[-1, 0] == pytest.approx(0.027, abs=0.0005)
    np.testing.assert_allclose(weighted.asymmetry, [0.854, 0.787, 0.725], atol=5e-4)


def test_meyran_2022_reproduction_with_the_deterministic_quadrature():
    # The quadrature gives the expectation over the gamma distribution; the re-run's numbers are
    # one 5000-radius sample (mean radius 0.950 µm vs 0.96 µm; its <r^2> is 2.1 % low). The
    # relative standard error of a 5000-sample mean of r^2 is sqrt(216/144)/sqrt(5000) = 1.7 %,
    # so absolute values get 4 % (2 sigma + rounding); ratios and albedos are far less noisy.
    table = particle_optics(DUST, dust_index(), RGB_NM, phase_average="number",
                            cache_directory=False)
    np.testing.assert_allclose(table.single_scattering_albedo, [0.667, 0.812, 0.956],
                               atol=0.002)
    c_ext, c_sca = table.extinction_cross_section_m2, table.scattering_cross_section_m2
    assert c_ext[2] / c_ext[0] == pytest.approx(1.052, rel=0.5 * PERCENT)
    assert c_sca[2] / c_sca[0] == pytest.approx(1.508, rel=0.5 * PERCENT)
    assert c_ext[0] == pytest.approx(8.63e-12, rel=4 * PERCENT)
    np.testing.assert_allclose(table.phase[0], [17.07, 9.21, 5.31], rtol=4 * PERCENT)
    np.testing.assert_allclose(table.phase[-1], [0.0538, 0.0846, 0.1058], rtol=4 * PERCENT)


# ----- Cache --------------------------------------------------------------------------------

def small_dust_table(cache_directory, **kwargs):
    return particle_optics(DUST, dust_index(), RGB_NM, n_radii=200,
                           cache_directory=cache_directory, **kwargs)


def test_second_call_loads_from_disk(tmp_path, monkeypatch):
    first = small_dust_table(tmp_path)
    files = list((tmp_path / "mie").glob("*.npz"))
    assert len(files) == 1

    def no_compute():
        raise AssertionError("computed again instead of loading the cache")

    monkeypatch.setattr(mie, "_import_miepython", no_compute)
    second = small_dust_table(tmp_path)
    for name, array in first.arrays().items():
        np.testing.assert_array_equal(getattr(second, name), array)
    with pytest.raises(AssertionError, match="computed again"):
        small_dust_table(tmp_path, phase_average="number")  # another key: not cached


def test_corrupt_cache_file_is_recomputed(tmp_path):
    first = small_dust_table(tmp_path)
    (path,) = (tmp_path / "mie").glob("*.npz")
    path.write_bytes(path.read_bytes()[:500])  # truncated
    again = small_dust_table(tmp_path)
    np.testing.assert_array_equal(again.phase, first.phase)
    (path,) = (tmp_path / "mie").glob("*.npz")
    assert path.stat().st_size > 500  # rewritten


def test_default_cache_directory_is_used_for_none(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path))
    small_dust_table(None)
    assert len(list((tmp_path / "mie").glob("*.npz"))) == 1


def test_progress_reports_each_wavelength():
    calls = []
    small_dust_table(False, progress=lambda done, total, stage: calls.append((done, total, stage)))
    assert calls == [(1, 3, "mie"), (2, 3, "mie"), (3, 3, "mie")]


# ----- MieOptics ------------------------------------------------------------------------------

def test_mie_optics_is_constituent_optics_with_interpolated_cross_sections():
    table = small_dust_table(False)
    optics = MieOptics(table)
    assert isinstance(optics.phase, TabulatedPhase) and isinstance(optics.phase, PhaseFunction)
    c_ext = table.extinction_cross_section_m2
    np.testing.assert_allclose(optics.extinction_per_density(np.array(RGB_NM)), c_ext, rtol=1e-15)
    np.testing.assert_allclose(optics.extinction_per_density(np.array([400.0, 495.0, 900.0])),
                               [c_ext[0], (c_ext[0] + c_ext[1]) / 2, c_ext[2]], rtol=1e-14)
    np.testing.assert_allclose(optics.scattering_per_density(np.array([550.0])),
                               table.scattering_cross_section_m2[1], rtol=1e-15)
    for shape in [(), (5,), (2, 3)]:
        assert optics.scattering_per_density(np.full(shape, 500.0)).shape == shape
    # TabulatedPhase renormalises its log-linear interpolant; the table is normalised already.
    np.testing.assert_allclose(optics.phase.evaluate(MU, np.array(RGB_NM)), table.phase,
                               rtol=1e-4)
    np.testing.assert_allclose(optics.phase.asymmetry(np.array(RGB_NM)), table.asymmetry,
                               atol=1e-4)


def test_mie_optics_repr_names_inputs_and_table_hash_not_arrays():
    a = MieOptics(small_dust_table(False))
    b = MieOptics(small_dust_table(False, phase_average="number"))
    text = repr(a)
    assert "ModifiedGamma(effective_radius_m=1.6e-06, effective_variance=0.2)" in text
    assert a.table.sha256() in text and "array" not in text and len(text) < 400
    assert repr(b) != text


# ----- Bad inputs ----------------------------------------------------------------------------

@pytest.mark.parametrize(("kwargs", "message"), [
    (dict(wavelengths_nm=[550.0, 440.0]), "must be finite, > 0 and strictly increasing"),
    (dict(wavelengths_nm=[-1.0]), "must be finite, > 0 and strictly increasing"),
    (dict(n_radii=1), "n_radii = 1 must be an integer >= 2"),
    (dict(phase_average="mass"), "phase_average = 'mass'; allowed: scattering, number"),
    (dict(method="rayleigh"), "method = 'rayleigh'; allowed: mie, ada"),
    (dict(index=1.5 + 0j), r"index = \(1.5\+0j\) must be a ComplexIndex"),
    (dict(distribution=Monodisperse(1e-3)), "largest size parameter .* exceeds 2000"),
    (dict(index=ComplexIndex.constant(1.0)), "do not scatter"),
])
def test_bad_inputs_raise_input_error(kwargs, message):
    arguments = dict(distribution=Monodisperse(1e-6), index=ComplexIndex.constant(1.5),
                     wavelengths_nm=[550.0], cache_directory=False) | kwargs
    with pytest.raises(InputError, match=message):
        particle_optics(**arguments)
