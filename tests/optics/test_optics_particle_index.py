"""Particle refractive indices: shipped tables against their sources, Maxwell Garnett checks."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.optics.particle_index import (
    MATERIALS,
    ComplexIndex,
    load_material,
    maxwell_garnett,
)

os.environ.setdefault("MIEPYTHON_USE_JIT", "1")
miepython = pytest.importorskip("miepython")


def test_every_material_loads_with_k_non_negative():
    for name in MATERIALS:
        m = load_material(name).at(np.linspace(300.0, 1000.0, 71))
        assert np.all(np.isfinite(m)) and np.all(m.real > 1.0) and np.all(m.imag >= 0.0)


def test_hematite_table_is_the_cosmoscout_mars_ehlers_table():
    # CosmoScout VR mars_ehlers.json (inclusion ior): 48 rows 0.36-0.83 µm; spot values.
    hematite = load_material("hematite")
    assert hematite.wavelengths_nm == tuple(float(w) for w in range(360, 831, 10))
    np.testing.assert_array_equal(hematite.at([360.0, 440.0, 550.0, 680.0, 830.0]),
                                  [2.211 + 0.987j, 2.766 + 0.936j, 2.927 + 0.460j,
                                   2.703 + 0.083j, 2.566 + 0.059j])


def test_water_table_is_segelstein_1981_as_shipped_by_miepython():
    # Independent read of miepython's file (wavelength in µm, n, k): every shipped row matches.
    source = Path(miepython.__file__).parent / "data" / "segelstein81_index.txt"
    reference = np.loadtxt(source, skiprows=4)
    water = load_material("water")
    wl = np.asarray(water.wavelengths_nm)
    assert wl[0] <= 300.0 and wl[-1] >= 1000.0
    rows = np.searchsorted(reference[:, 0], wl / 1000.0 - 1e-9)
    np.testing.assert_allclose(reference[rows, 0] * 1000.0, wl, rtol=1e-12)
    np.testing.assert_array_equal(water.n, reference[rows, 1])
    np.testing.assert_array_equal(water.k, reference[rows, 2])


def test_water_at_550_nm():
    # Segelstein's compilation gives n = 1.33597 at 549.5 nm and 1.33566 at 554.6 nm (so 1.3359
    # at 550 nm; pure water at 20 °C is about 1.334); k is ~2.5e-9 there.
    m = load_material("water").at(550.0)
    assert 1.333 < m.real < 1.337
    assert 1e-9 < m.imag < 5e-9


def test_soot_and_costa_mars_dust():
    # Bond & Bergstrom (2006): 1.95 + 0.79i, the same at every wavelength.
    np.testing.assert_array_equal(load_material("soot").at([400.0, 700.0]), [1.95 + 0.79j] * 2)
    # Costa (2020) Table 1 (Meyran 2022 Table 3.7): n = 1.52, k = 0.013/0.006/0.001 at 440/550/680.
    np.testing.assert_array_equal(load_material("mars-dust-costa").at([440.0, 550.0, 680.0]),
                                  [1.52 + 0.013j, 1.52 + 0.006j, 1.52 + 0.001j])


def test_tables_interpolate_linearly_and_hold_constant_outside():
    index = ComplexIndex.table([500.0, 400.0], [1.6, 1.4], [0.02, 0.0])
    np.testing.assert_allclose(index.at([300.0, 450.0, 600.0]),
                               [1.4 + 0.0j, 1.5 + 0.01j, 1.6 + 0.02j], rtol=1e-15)
    assert index.at(np.zeros((2, 3)) + 450.0).shape == (2, 3)
    assert ComplexIndex.constant(1.33).at([400.0, 500.0]).tolist() == [1.33 + 0j, 1.33 + 0j]


def test_maxwell_garnett_end_members_are_host_and_inclusion():
    hematite = load_material("hematite")
    wl = np.array([360.0, 440.0, 550.0, 830.0])
    np.testing.assert_allclose(maxwell_garnett(1.5, hematite, 0.0).at(wl), 1.5 + 0j, rtol=1e-15)
    np.testing.assert_allclose(maxwell_garnett(1.5, hematite, 1.0).at(wl), hematite.at(wl),
                               rtol=1e-14)


def test_maxwell_garnett_reproduces_meyran_2022_mixed_hematite():
    # Meyran 2022 App. A.2.1 re-run: 3 % hematite in 1.5 + 0i, printed to 4 decimals (tolerance:
    # half a unit in the last digit). The reference prints Im < 0 (miepython's sign); we keep
    # k >= 0.
    mixed = maxwell_garnett(1.5 + 0j, load_material("hematite"), 0.03)
    m = mixed.at([440.0, 550.0, 680.0])
    np.testing.assert_allclose(m.real, [1.5342, 1.5337, 1.5290], atol=0.5e-4)
    np.testing.assert_allclose(m.imag, [0.0154, 0.0072, 0.0015], atol=0.5e-4)


def test_maxwell_garnett_dilute_limit_is_the_first_order_expansion():
    # m^2 = m0^2 (1 + 3 v beta) + O(v^2), beta = (mA^2 - m0^2) / (mA^2 + 2 m0^2).
    m0, m_a = 1.5 + 0.0j, 2.766 + 0.936j
    beta = (m_a**2 - m0**2) / (m_a**2 + 2 * m0**2)
    for v in (1e-3, 1e-4):
        m = maxwell_garnett(m0, m_a, v).at(550.0)
        first_order = m0**2 * (1 + 3 * v * beta)
        # the next term is 3 v^2 beta^2 m0^2: the gap must shrink as v^2
        assert abs(m**2 - first_order) == pytest.approx(abs(3 * v**2 * beta**2 * m0**2),
                                                        rel=5 * v)


def test_maxwell_garnett_of_two_tables_is_exact_on_both_grids():
    host = ComplexIndex.table([400.0, 600.0], [1.50, 1.52], [0.0, 0.001])
    inclusion = ComplexIndex.table([500.0, 700.0], [2.9, 2.7], [0.6, 0.08])
    mixed = maxwell_garnett(host, inclusion, 0.1)
    assert mixed.wavelengths_nm == (400.0, 500.0, 600.0, 700.0)
    for wl in mixed.wavelengths_nm:
        direct = maxwell_garnett(host.at(wl), inclusion.at(wl), 0.1).at(wl)
        assert mixed.at(wl) == pytest.approx(direct, rel=1e-15)


@pytest.mark.parametrize(("make", "message"), [
    (lambda: ComplexIndex.constant(1.5, -0.01), r"k = \[-0.01\] must be finite and >= 0"),
    (lambda: ComplexIndex.constant(0.0), r"n = \[0.0\] must be finite and > 0"),
    (lambda: ComplexIndex.table([500.0, 500.0], [1.5, 1.5], [0, 0]), "strictly increasing"),
    (lambda: ComplexIndex.table([500.0], [1.5, 1.6], [0.0]), "must have one length"),
    (lambda: load_material("basalt"), "unknown particle material 'basalt'; allowed: hematite"),
    (lambda: maxwell_garnett(1.5, 2.0 + 1j, 1.2), r"volume_fraction = 1.2 must lie in \[0, 1\]"),
    (lambda: maxwell_garnett("glass", 2.0, 0.1), "host = 'glass' must be a ComplexIndex"),
])
def test_bad_inputs_raise_input_error(make, message):
    with pytest.raises(InputError, match=message):
        make()
