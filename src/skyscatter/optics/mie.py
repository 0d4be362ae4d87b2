r"""Optics of a population of spheres from Mie theory: cross-sections, asymmetry, phase table.

For a sphere of radius r and complex index m = n + i k (k >= 0) in vacuum at wavelength lambda,
x = 2 pi r / lambda, the Mie coefficients a_n, b_n (from miepython's `an_bn`, Wiscombe's
truncation n <= N(x) = x + 4.05 x^(1/3) + 2) give (Bohren & Huffman 1983, "Absorption and
Scattering of Light by Small Particles", Wiley, doi:10.1002/9783527618156, §4.4-4.5):

    Q_ext = (2/x^2) sum_n (2n+1) Re(a_n + b_n)                                      (eq. 4.62)
    Q_sca = (2/x^2) sum_n (2n+1) (|a_n|^2 + |b_n|^2)                                (eq. 4.61)
    g Q_sca = (4/x^2) [sum_n n(n+2)/(n+1) Re(a_n a*_{n+1} + b_n b*_{n+1})
                       + sum_n (2n+1)/(n(n+1)) Re(a_n b*_n)]                         (§4.5)
    S1 = sum_n (2n+1)/(n(n+1)) (a_n pi_n + b_n tau_n),  S2 = same with pi_n <-> tau_n  (eq. 4.74)
    p(theta) = (|S1|^2 + |S2|^2) / (2 pi x^2 Q_sca)  [sr^-1], 2 pi int p sin(theta) dtheta = 1

with the angular functions pi_n, tau_n of `angular_functions` (eq. 4.47), C = pi r^2 Q.

A population (`optics.size_distribution`) is averaged on its radius quadrature (number
fractions w_i): <C_ext> and <C_sca> are number means per particle, so that a number density
N [m^-3] gives beta = N <C>. The phase function is either
  - "scattering": sum_i w_i C_sca,i p_i / sum_i w_i C_sca,i, the phase function of the light the
    population scatters (Hansen & Travis 1974, doi:10.1007/BF00168069; the physical one),
  - "number": sum_i w_i p_i, the plain mean of the normalised per-particle phase functions that
    Meyran's Mars thesis used (2022, Hochschule Hannover, App. A.2); it over-weights small
    particles (at 440 nm for its dust the forward peak is 2.4x lower, docs/physics/mie.md). Kept to
    reproduce its numbers.
The asymmetry parameter is that of the tabulated phase function (C_sca-weighted or plain mean
of the per-particle g).

Speed. The population intensity sum_i omega_i (|S1_i|^2 + |S2_i|^2) is a quadratic form in the
angular functions: with u_n = c_n a_n, v_n = c_n b_n, c_n = (2n+1)/(n(n+1)),
    sum_i omega_i (|S1_i|^2 + |S2_i|^2) = pi^T D pi + tau^T D tau + 2 pi^T E tau,
    D = Re sum_i omega_i (u_i u_i^H + v_i v_i^H),  E = Re sum_i omega_i (u_i v_i^H + v_i u_i^H),
(expand |S1|^2 = S1 S1* and add |S2|^2). D and E are sums over radii, built chunk by chunk with
one BLAS product each (radii sorted by size, each chunk padded only to its own largest order),
and pi_n, tau_n are computed once for all angles and wavelengths. The cost is
O(n_radii N^2) + O(N^2 n_angle) per wavelength instead of O(n_radii N n_angle).

`method="ada"` takes extinction and absorption from van de Hulst's anomalous diffraction
approximation (`anomalous_diffraction_efficiencies`) and keeps the Mie phase function and
asymmetry (ADA has none); the "scattering" phase weights remain the Mie C_sca.

Angles (`MIE_ANGLES_DEG`): the forward peak of a sphere is about 1/x rad wide (diffraction):
0.38° for x = 150 (r = 8.7 µm, the largest radius of the Meyran 2022 dust quadrature, at 360 nm).
Steps of 0.02° up to 2°, 0.1° up to 10° and 0.25° up to 180° (861 angles) put 19 angles inside
that width, and still 5 for x = 500; a population's peak is wider (its C_sca-weighted radius).

Results are cached on disk (`skyscatter.disk_cache`) under <cache dir>/mie/, keyed by a SHA-256
of everything that changes them; a corrupt or foreign entry is recomputed.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.disk_cache import TableCache, default_cache_directory
from skyscatter.errors import InputError
from skyscatter.optics.particle_index import ComplexIndex
from skyscatter.optics.phase import PhaseFunction, TabulatedPhase, angle_blended_phase
from skyscatter.optics.size_distribution import SizeDistribution

__all__ = [
    "MAX_SIZE_PARAMETER",
    "METHODS",
    "MIE_ANGLES_DEG",
    "MIE_CODE_VERSION",
    "MIE_WAVELENGTHS_NM",
    "PHASE_AVERAGES",
    "MieOptics",
    "ParticleOpticsTable",
    "angular_functions",
    "anomalous_diffraction_efficiencies",
    "particle_optics",
]

MIE_CODE_VERSION = 1  # bump when a change in this module changes the tables (cache key)
MAX_SIZE_PARAMETER = 2000.0  # largest x = 2 pi r / lambda: N ~ 2050 orders, D and E ~ 70 MB
_CHUNK_RADII = 128  # radii per BLAS product
PHASE_AVERAGES = ("scattering", "number")  # `particle_optics(phase_average=...)`
METHODS = ("mie", "ada")  # `particle_optics(method=...)`

MIE_ANGLES_DEG = np.concatenate([np.linspace(0.0, 2.0, 101)[:-1],
                                 np.linspace(2.0, 10.0, 81)[:-1],
                                 np.linspace(10.0, 180.0, 681)])
MIE_ANGLES_DEG.flags.writeable = False
MIE_WAVELENGTHS_NM = np.arange(360.0, 901.0, 10.0)  # configs' Mie tables, interpolated between
MIE_WAVELENGTHS_NM.flags.writeable = False


@dataclass(frozen=True, eq=False)
class ParticleOpticsTable:
    """Optics of one particle population per wavelength (made by `particle_optics`).

    Parameters
    ----------
    wavelengths_nm : ndarray, shape (n_wl,)
        Wavelengths, strictly increasing. [nm]
    angles_deg : ndarray, shape (n_angle,)
        Scattering angles, 0 to 180. [deg]
    extinction_cross_section_m2, scattering_cross_section_m2 : ndarray, shape (n_wl,)
        Number-mean cross-sections per particle. [m^2]
    asymmetry : ndarray, shape (n_wl,)
        <cos(scattering angle)> of `phase`. [-]
    phase : ndarray, shape (n_angle, n_wl)
        Phase function, 2 pi int p sin(theta) dtheta = 1. [sr^-1]
    description : str
        What it was made from (distribution, method, averaging).
    """

    wavelengths_nm: np.ndarray
    angles_deg: np.ndarray
    extinction_cross_section_m2: np.ndarray
    scattering_cross_section_m2: np.ndarray
    asymmetry: np.ndarray
    phase: np.ndarray
    description: str = ""

    _ARRAYS = ("wavelengths_nm", "angles_deg", "extinction_cross_section_m2",
               "scattering_cross_section_m2", "asymmetry", "phase")

    def __post_init__(self) -> None:
        for name in self._ARRAYS:
            value = np.array(getattr(self, name), dtype=np.float64)
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        n_wl, n_angle = self.wavelengths_nm.size, self.angles_deg.size
        for name in self._ARRAYS[2:5]:
            if getattr(self, name).shape != (n_wl,):
                raise InputError(f"ParticleOpticsTable: {name} has shape "
                                 f"{getattr(self, name).shape}, expected ({n_wl},)", key=name)
        if self.phase.shape != (n_angle, n_wl):
            raise InputError(f"ParticleOpticsTable: phase has shape {self.phase.shape}, "
                             f"expected {(n_angle, n_wl)}", key="phase")

    @property
    def single_scattering_albedo(self) -> np.ndarray:
        """<C_sca> / <C_ext>, shape (n_wl,). [-]"""
        return self.scattering_cross_section_m2 / self.extinction_cross_section_m2

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays by field name (what the cache stores)."""
        return {name: getattr(self, name) for name in self._ARRAYS}

    def sha256(self) -> str:
        """SHA-256 of all arrays: identifies the table (used in `MieOptics.__repr__`)."""
        digest = hashlib.sha256()
        for name, array in self.arrays().items():
            digest.update(name.encode())
            digest.update(np.ascontiguousarray(array).tobytes())
        return digest.hexdigest()


def angular_functions(mu: ArrayLike, n_max: int) -> tuple[np.ndarray, np.ndarray]:
    r"""Mie angular functions pi_n(mu), tau_n(mu) for n = 1 ... n_max.

    pi_n = (2n - 1)/(n - 1) mu pi_{n-1} - n/(n - 1) pi_{n-2},  tau_n = n mu pi_n - (n + 1) pi_{n-1},
    pi_0 = 0, pi_1 = 1 (Bohren & Huffman 1983, eq. 4.47, doi:10.1002/9783527618156); upward
    recurrence, stable for all n. At mu = 1: pi_n = tau_n = n(n+1)/2.

    Parameters
    ----------
    mu : array_like, shape (n_angle,)
        Cosine of the scattering angle. [-]
    n_max : int
        Highest order, >= 1.

    Returns
    -------
    pi, tau : ndarray, shape (n_max, n_angle)
        Row n - 1 holds order n. [-]
    """
    mu = np.atleast_1d(np.asarray(mu, dtype=np.float64))
    pi = np.empty((n_max, mu.size))
    tau = np.empty((n_max, mu.size))
    previous = np.zeros(mu.size)  # pi_0
    current = np.ones(mu.size)    # pi_1
    for n in range(1, n_max + 1):
        if n > 1:
            previous, current = current, ((2 * n - 1) * mu * current - n * previous) / (n - 1)
        pi[n - 1] = current
        tau[n - 1] = n * mu * current - (n + 1) * previous
    return pi, tau


def _k_function(w: np.ndarray) -> np.ndarray:
    """van de Hulst's K(w) = 1/2 + e^-w / w + (e^-w - 1) / w^2 (complex w, Re w >= 0).

    Below |w| = 0.1 its series sum_{p>=1} (-1)^(p+1) (p+1) w^p / (p+2)! (6 terms, error < 1e-10
    relative) replaces the closed form, which cancels there.
    """
    w = np.asarray(w, dtype=np.complex128)
    small = np.abs(w) < 0.1
    safe = np.where(small, 1.0, w)
    closed = 0.5 + np.exp(-safe) / safe + np.expm1(-safe) / safe**2
    series = sum((-1) ** (p + 1) * (p + 1) * w**p / math.factorial(p + 2) for p in range(1, 7))
    return np.where(small, series, closed)


def anomalous_diffraction_efficiencies(size_parameter: ArrayLike,
                                       index: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Extinction and absorption efficiencies of a sphere in the anomalous diffraction approx.

    Q_ext = 4 Re K(rho tan(beta) + i rho),  Q_abs = 2 K(4 x k),
    K(w) = 1/2 + e^-w / w + (e^-w - 1) / w^2,  rho = 2 x (n - 1),  tan(beta) = k / (n - 1),
    van de Hulst (1957), "Light Scattering by Small Particles", Wiley, §11.22 (the Q_ext form is
    the same as Meyran 2022 Eq. 2.32, written through K so that n = 1 needs no tan beta). Valid for
    |m - 1| << 1 and x >> 1; Q_ext -> 2 for x -> infinity. Q_sca = Q_ext - Q_abs.

    Parameters
    ----------
    size_parameter : array_like, shape S
        x = 2 pi r / lambda, >= 0. [-]
    index : array_like, broadcastable to S
        Complex refractive index n + i k, k >= 0. [-]

    Returns
    -------
    q_ext, q_abs : ndarray, shape S
        Extinction and absorption efficiencies. [-]
    """
    x = np.asarray(size_parameter, dtype=np.float64)
    m = np.asarray(index, dtype=np.complex128)
    rho = 2.0 * x * (m.real - 1.0)
    q_ext = 4.0 * _k_function(2.0 * x * m.imag + 1j * rho).real
    q_abs = 2.0 * _k_function(4.0 * x * m.imag + 0j).real
    return q_ext, q_abs


def _import_miepython():
    """miepython with its numba backend (the variable is read when miepython is imported)."""
    os.environ.setdefault("MIEPYTHON_USE_JIT", "1")
    try:
        import miepython
    except ImportError:
        raise InputError("Mie optics need the miepython package (pip install 'miepython>=3.3')",
                         key="method", value="mie", allowed="miepython installed") from None
    return miepython


def _population_at_wavelength(an_bn, m: complex, x: np.ndarray, w: np.ndarray, pi: np.ndarray,
                              tau: np.ndarray, phase_average: str):
    """Mie sums over one radius quadrature at one wavelength.

    x: size parameters (n_r,), sorted (so that each chunk's orders are alike); w: number
    fractions (n_r,); pi, tau: angular functions (N_max, n_angle). Returns the number means
    <Q_ext x^2>, <Q_sca x^2> (times pi / k^2: cross-sections), the asymmetry and the phase
    function (n_angle,) [sr^-1].
    """
    m_mie = m.conjugate()  # miepython's convention is n - i k
    coefficients = [an_bn(m_mie, float(xi)) for xi in x]
    lengths = np.array([len(a) for a, _ in coefficients])
    n_max = pi.shape[0]
    d = np.zeros((n_max, n_max))
    e = np.zeros((n_max, n_max))
    ext_x2 = np.empty(x.size)
    sca_x2 = np.empty(x.size)
    g_sca_x2 = np.empty(x.size)
    for start in range(0, x.size, _CHUNK_RADII):
        chunk = slice(start, min(start + _CHUNK_RADII, x.size))
        n_c = int(lengths[chunk].max())
        a = np.zeros((lengths[chunk].size, n_c + 1), dtype=np.complex128)  # +1: a_{n+1} = 0
        b = np.zeros_like(a)
        for row, (an, bn) in enumerate(coefficients[chunk]):
            a[row, :an.size] = an
            b[row, :bn.size] = bn
        n = np.arange(1.0, n_c + 2.0)
        ext_x2[chunk] = 2.0 * ((2 * n + 1) * (a + b).real).sum(axis=1)
        sca_x2[chunk] = 2.0 * ((2 * n + 1) * (np.abs(a) ** 2 + np.abs(b) ** 2)).sum(axis=1)
        g_sca_x2[chunk] = 4.0 * (
            (n[:-1] * (n[:-1] + 2) / (n[:-1] + 1)
             * (a[:, :-1] * a[:, 1:].conj() + b[:, :-1] * b[:, 1:].conj()).real).sum(axis=1)
            + ((2 * n + 1) / (n * (n + 1)) * (a * b.conj()).real).sum(axis=1))
        # number: p_i = (|S1|^2 + |S2|^2) / (2 pi x^2 Q_sca); scattering: normalised below
        omega = w[chunk] / (np.pi * sca_x2[chunk]) if phase_average == "number" else w[chunk]
        c = np.sqrt(omega)[:, None] * (2 * n[:-1] + 1) / (n[:-1] * (n[:-1] + 1))
        u = c * a[:, :-1]
        v = c * b[:, :-1]
        y = np.block([[u.real, v.real], [u.imag, v.imag]])
        r = y.T @ y  # Re of sum_i omega_i [u; v] [u; v]^H
        d[:n_c, :n_c] += r[:n_c, :n_c] + r[n_c:, n_c:]
        e[:n_c, :n_c] += r[:n_c, n_c:] + r[n_c:, :n_c]
    intensity = (pi * (d @ pi)).sum(axis=0) + (tau * (d @ tau)).sum(axis=0) \
        + 2.0 * (pi * (e @ tau)).sum(axis=0)
    mean_ext_x2 = float(np.sum(w * ext_x2))
    mean_sca_x2 = float(np.sum(w * sca_x2))
    if phase_average == "number":
        phase = 0.5 * intensity
        asymmetry = float(np.sum(w * g_sca_x2 / sca_x2))
    else:  # divide by 2 k^2 <C_sca> = 2 pi <x^2 Q_sca>
        phase = intensity / (2.0 * np.pi * mean_sca_x2)
        asymmetry = float(np.sum(w * g_sca_x2) / mean_sca_x2)
    return mean_ext_x2, mean_sca_x2, asymmetry, phase


def _check_inputs(wavelengths_nm: ArrayLike, n_radii: int, phase_average: str,
                  method: str) -> np.ndarray:
    wl = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    if wl.ndim != 1 or not np.all(np.isfinite(wl)) or np.any(wl <= 0.0) \
            or np.any(np.diff(wl) <= 0.0):
        raise InputError(f"wavelengths_nm = {wl!r} must be finite, > 0 and strictly increasing",
                         key="wavelengths_nm", value=wl, allowed="> 0 nm, increasing")
    if isinstance(n_radii, bool) or not isinstance(n_radii, int | np.integer) or n_radii < 2:
        raise InputError(f"n_radii = {n_radii!r} must be an integer >= 2", key="n_radii",
                         value=n_radii, allowed="integer >= 2")
    if phase_average not in PHASE_AVERAGES:
        raise InputError(f"phase_average = {phase_average!r}; allowed: "
                         f"{', '.join(PHASE_AVERAGES)}", key="phase_average",
                         value=phase_average, allowed=", ".join(PHASE_AVERAGES))
    if method not in METHODS:
        raise InputError(f"method = {method!r}; allowed: {', '.join(METHODS)}", key="method",
                         value=method, allowed=", ".join(METHODS))
    return wl


def _cache_metadata(distribution: SizeDistribution, radii: np.ndarray, weights: np.ndarray,
                    m: np.ndarray, wl: np.ndarray, n_radii: int, phase_average: str,
                    method: str) -> dict:
    """Everything that changes a table, as JSON-ready values (the cache compares it in full)."""
    quadrature = hashlib.sha256(radii.tobytes() + weights.tobytes()).hexdigest()
    try:
        miepython_version = version("miepython")
    except PackageNotFoundError:
        miepython_version = "not installed"
    return {"distribution": repr(distribution), "quadrature_sha256": quadrature,
            "n_radii": int(n_radii), "wavelengths_nm": wl.tolist(),
            "index": [[float(v.real), float(v.imag)] for v in m],
            "angles_sha256": hashlib.sha256(MIE_ANGLES_DEG.tobytes()).hexdigest(),
            "method": method, "phase_average": phase_average,
            "miepython": miepython_version, "code_version": MIE_CODE_VERSION}


def particle_optics(distribution: SizeDistribution, index: ComplexIndex,
                    wavelengths_nm: ArrayLike, *, n_radii: int = 5000,
                    phase_average: str = "scattering", method: str = "mie",
                    cache_directory: Path | str | None | bool = None,
                    progress: Callable[[int, int, str], None] | None = None,
                    ) -> ParticleOpticsTable:
    r"""Cross-sections, asymmetry and phase table of a particle population (module docstring).

    Parameters
    ----------
    distribution : SizeDistribution
        Radii and number fractions (`optics.size_distribution`), averaged on
        `distribution.quadrature(n_radii)`.
    index : ComplexIndex
        Refractive index of the particles, m = n + i k, k >= 0 (`optics.particle_index`). [-]
    wavelengths_nm : array_like, shape (n_wl,)
        Vacuum wavelengths, strictly increasing; the medium is taken as vacuum. [nm]
    n_radii : int
        Nodes of the radius quadrature (5000 matches the sample count of Meyran 2022, App. A.2).
    phase_average : str
        "scattering" (C_sca-weighted, physical) or "number" (plain mean, Meyran 2022's thesis).
    method : str
        "mie" (Mie extinction and scattering) or "ada" (anomalous diffraction extinction and
        absorption, Mie phase function and asymmetry).
    cache_directory : path, None or False
        Cache root (entries go in its mie/ folder); None: `default_cache_directory()`;
        False: no cache.
    progress : callable(done, total, stage), optional
        Called after each wavelength.

    Returns
    -------
    ParticleOpticsTable
        On `MIE_ANGLES_DEG`; cross-sections are number means per particle. [m^2, sr^-1]
    """
    wl = _check_inputs(wavelengths_nm, n_radii, phase_average, method)
    if not isinstance(index, ComplexIndex):
        raise InputError(f"index = {index!r} must be a ComplexIndex", key="index", value=index,
                         allowed="ComplexIndex")
    radii, weights = distribution.quadrature(n_radii)
    m = index.at(wl)
    if np.any(m == 1.0):
        raise InputError(f"particles of index 1 + 0i (at {wl[m == 1.0].tolist()} nm) do not "
                         "scatter: they are the medium (vacuum)", key="index", value=index,
                         allowed="m != 1 + 0i")
    x_max = 2.0 * np.pi * float(np.max(radii)) / (wl[0] * 1e-9)
    if x_max > MAX_SIZE_PARAMETER:
        raise InputError(f"largest size parameter 2 pi r / lambda = {x_max:.0f} (r = "
                         f"{np.max(radii):.3g} m at {wl[0]:g} nm) exceeds {MAX_SIZE_PARAMETER:g}",
                         key="distribution", value=repr(distribution),
                         allowed=f"x <= {MAX_SIZE_PARAMETER:g}")
    description = (f"{distribution!r}, m = {m[0]:.5g} ... {m[-1]:.5g}, n_radii={n_radii}, "
                   f"method={method!r}, phase_average={phase_average!r}")
    cache = None
    if cache_directory is not False:
        root = default_cache_directory() if cache_directory in (None, True) else cache_directory
        cache = TableCache(Path(root) / "mie")
        metadata = _cache_metadata(distribution, radii, weights, m, wl, n_radii, phase_average,
                                   method)
        key = hashlib.sha256(json.dumps(metadata, sort_keys=True).encode()).hexdigest()
        arrays, _ = cache.load(key, metadata)
        if arrays is not None and set(arrays) == set(ParticleOpticsTable._ARRAYS):
            return ParticleOpticsTable(**arrays, description=description)

    an_bn = _import_miepython().an_bn
    mu = np.cos(np.deg2rad(MIE_ANGLES_DEG))
    n_max = int(x_max + 4.05 * x_max ** (1.0 / 3.0) + 2.0)  # Wiscombe's N(x), as in an_bn
    pi, tau = angular_functions(mu, n_max)
    c_ext = np.empty(wl.size)
    c_sca = np.empty(wl.size)
    asymmetry = np.empty(wl.size)
    phase = np.empty((mu.size, wl.size))
    for j, (wavelength_nm, m_j) in enumerate(zip(wl, m, strict=True)):
        k = 2.0 * np.pi / (wavelength_nm * 1e-9)
        x = k * radii
        ext_x2, sca_x2, asymmetry[j], phase[:, j] = _population_at_wavelength(
            an_bn, complex(m_j), x, weights, pi, tau, phase_average)
        if method == "ada":
            q_ext, q_abs = anomalous_diffraction_efficiencies(x, m_j)
            ext_x2 = float(np.sum(weights * q_ext * x**2))
            sca_x2 = float(np.sum(weights * (q_ext - q_abs) * x**2))
        c_ext[j] = np.pi * ext_x2 / k**2  # C = pi r^2 Q = pi x^2 Q / k^2
        c_sca[j] = np.pi * sca_x2 / k**2
        if progress is not None:
            progress(j + 1, wl.size, "mie")
    table = ParticleOpticsTable(wl, MIE_ANGLES_DEG, c_ext, c_sca, asymmetry, phase,
                                description=description)
    if cache is not None:
        cache.store(key, table.arrays(), metadata)
    return table


@dataclass(frozen=True, eq=False)
class MieOptics:
    """`ConstituentOptics` of a particle population from a `ParticleOpticsTable`.

    The density profile of the constituent is a number density [m^-3]: per-density values are
    the per-particle cross-sections [m^2], interpolated linearly in wavelength and held constant
    outside the table. `phase` is a `TabulatedPhase` of the table (log-linear in angle, linear
    in wavelength), or, when `blend` is given, the table's phase function blended into `blend`
    linearly in angle (`optics.phase.angle_blended_phase`: Meyran 2022's hybrid Mars dust keeps
    the Mie forward peak and takes Costa's double Henyey-Greenstein in back scattering). `repr`
    names the inputs and the SHA-256 of the table, never the arrays.
    """

    table: ParticleOpticsTable
    blend: PhaseFunction | None = None
    phase: TabulatedPhase = field(init=False)

    def __post_init__(self) -> None:
        phase = TabulatedPhase(self.table.angles_deg, self.table.phase, self.table.wavelengths_nm)
        if self.blend is not None:
            phase = angle_blended_phase(phase, self.blend, self.table.angles_deg,
                                        self.table.wavelengths_nm)
        object.__setattr__(self, "phase", phase)

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction cross-section per particle on `wavelengths_nm` [nm]. [m^2]"""
        return np.interp(np.asarray(wavelengths_nm, dtype=np.float64), self.table.wavelengths_nm,
                         self.table.extinction_cross_section_m2)

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Scattering cross-section per particle on `wavelengths_nm` [nm]. [m^2]"""
        return np.interp(np.asarray(wavelengths_nm, dtype=np.float64), self.table.wavelengths_nm,
                         self.table.scattering_cross_section_m2)

    def __repr__(self) -> str:
        wl = self.table.wavelengths_nm
        return (f"MieOptics({self.table.description!r}, wavelengths_nm={wl[0]:g}-{wl[-1]:g} "
                f"({wl.size}), table_sha256={self.table.sha256()!r}, blend={self.blend!r})")
