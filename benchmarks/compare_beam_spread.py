"""Accuracy: a low sun's beam through forward-peaked particles, `transport.beam_spread` against
a forward Monte Carlo of the light scattered only in peaks (docs/validation.md, "A low sun's
beam spread by the peaks").

One band of a preset (default `mars-physical` at 566 nm) with the tables' peaks (clipped at
`TableResolution.truncation_angle_deg`): photons from the sun over the planet's disk (an
annulus that reaches sun zenith angles from 70 deg on), peak events by delta tracking with the
peak drawn in 3-D, everything else (absorption, the smooth part's scattering) a loss, and the
light's track length in (altitude, sun zenith) cells; run twice, with the peaks deflecting
and with them keeping the light on its line (delta-M's scaled beam, by the same estimator).
Prints per cell the Monte Carlo's ratio of the two and the solver's G at the cell's centre.

Run: PYTHONPATH=src python benchmarks/compare_beam_spread.py [--atmosphere mars-physical]
     [--band-nm 566] [--photons 1200000]
About 4 minutes on 2 cores with the defaults.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from numba import njit

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport._kernels import density_at
from skyscatter.transport._monte_carlo_kernels import rotate
from skyscatter.transport.beam_spread import beam_spread
from skyscatter.transport.phase_truncation import truncate_forward_peak
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents
from skyscatter.transport.tables import TABLE_MIN_PEAK_FRACTION, TableResolution

ALTITUDE_EDGES_M = np.array([0.0, 1000.0, 3000.0, 6000.0])
SUN_ZENITH_EDGES_DEG = np.array([80.0, 82.0, 84.0, 86.0, 88.0])
STEP_M = 200.0


@njit(cache=True)
def _photons(n: int, seed: int, deflect: bool, bottom: float, top: float, rho_min: float,
             dz: float, peak_loss: np.ndarray, cdf: np.ndarray,
             angles: np.ndarray, altitude_edges: np.ndarray, zenith_edges: np.ndarray
             ) -> np.ndarray:
    """Loss-weighted track length of n photons per (altitude, sun zenith) cell, the sun along
    +z, photons entering on the annulus rho_min .. top of the disk facing it; `peak_loss`
    (2, n_z) the peak events' and the loss's coefficients [m^-1] on levels every dz."""
    np.random.seed(seed)
    out = np.zeros((altitude_edges.size - 1, zenith_edges.size - 1))
    majorant = peak_loss[0].max()
    here = np.empty(2)
    for _ in range(n):
        rho = math.sqrt(rho_min ** 2 + np.random.random() * (top ** 2 - rho_min ** 2))
        phi = 2.0 * math.pi * np.random.random()
        px, py, pz = rho * math.cos(phi), rho * math.sin(phi), math.sqrt(top ** 2 - rho ** 2)
        dx, dy, dz_ = 0.0, 0.0, -1.0
        weight = 1.0
        alive = True
        while alive:
            to_event = -math.log(1.0 - np.random.random()) / majorant
            while to_event > 0.0:
                ds = min(STEP_M, to_event)
                mx, my, mz = px + 0.5 * ds * dx, py + 0.5 * ds * dy, pz + 0.5 * ds * dz_
                r = math.sqrt(mx * mx + my * my + mz * mz)
                if r < bottom or (r > top and mx * dx + my * dy + mz * dz_ > 0.0):
                    alive = False
                    break
                altitude = r - bottom
                density_at(altitude, dz, peak_loss, here)
                attenuation = math.exp(-here[1] * ds)
                zenith = math.degrees(math.acos(min(1.0, max(-1.0, mz / r))))
                a = np.searchsorted(altitude_edges, altitude, side="right") - 1
                b = np.searchsorted(zenith_edges, zenith, side="right") - 1
                if 0 <= a < out.shape[0] and 0 <= b < out.shape[1]:
                    out[a, b] += weight * ds * math.sqrt(attenuation)
                weight *= attenuation
                px, py, pz = px + ds * dx, py + ds * dy, pz + ds * dz_
                to_event -= ds
            if not alive:
                break
            density_at(math.sqrt(px * px + py * py + pz * pz) - bottom, dz, peak_loss, here)
            if not deflect or np.random.random() * majorant >= here[0]:
                continue  # a null event, or a peak event that keeps the light on its line
            dx, dy, dz_ = rotate(dx, dy, dz_, math.cos(np.interp(np.random.random(), cdf, angles)),
                                 2.0 * math.pi * np.random.random())
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmosphere", default="mars-physical")
    parser.add_argument("--band-nm", type=float, default=566.0)
    parser.add_argument("--photons", type=float, default=1.2e6)
    args = parser.parse_args()
    profile = load_atmosphere(args.atmosphere).optical_profile(wavelength_grid(8))
    w = int(np.argmin(np.abs(profile.wavelengths_nm - args.band_nm)))
    truncation = TableResolution().truncation_angle_deg
    scatterers = scattering_constituents(profile)
    phase = sample_phase_functions(profile, scatterers, TableResolution().phase_angles)
    smooth, fraction = truncate_forward_peak(phase, truncation,
                                             min_fraction=TABLE_MIN_PEAK_FRACTION)
    removed = np.zeros_like(profile.scattering_per_density)
    removed[list(scatterers)] = fraction * profile.scattering_per_density[list(scatterers)]
    clipped = int(np.argmax(fraction[:, w]))  # the constituent with the most peak
    peak_phase = ((phase[clipped] - (1.0 - fraction[clipped]) * smooth[clipped])
                  / np.where(fraction[clipped] > 0.0, fraction[clipped], 1.0))
    spread = beam_spread(profile, removed, peak_phase, truncation)
    if spread is None:
        raise SystemExit(f"{args.atmosphere}: the tables keep delta-M's beam (beam_spread)")

    theta = np.linspace(0.0, np.pi, peak_phase.shape[0])
    angles = np.linspace(0.0, np.radians(truncation), 4001)
    density = np.interp(angles, theta, peak_phase[:, w]) * np.sin(angles)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1])
                                           * np.diff(angles))])
    levels = profile.altitudes_m
    peak = profile.density.T @ removed[:, w]
    loss = profile.density.T @ profile.extinction_per_density[:, w] - peak
    bottom, top = profile.bottom_radius_m, profile.top_radius_m
    rho_min = bottom * math.sin(math.radians(70.0))
    tallies = []
    for deflect in (False, True):
        start = time.perf_counter()
        tallies.append(_photons(int(args.photons), 7 + deflect, deflect, bottom, top, rho_min,
                                float(levels[1] - levels[0]), np.stack([peak, loss]),
                                cdf / cdf[-1],
                                angles, ALTITUDE_EDGES_M, SUN_ZENITH_EDGES_DEG))
        print(f"Monte Carlo, peaks {'deflecting' if deflect else 'on the line'}: "
              f"{time.perf_counter() - start:.0f} s")
    ratio = tallies[1] / tallies[0]
    print(f"\n{args.atmosphere}, {profile.wavelengths_nm[w]:.1f} nm: the light scattered only "
          "in peaks over delta-M's scaled beam, Monte Carlo | beam_spread's G at the centre")
    print("| altitude | " + " | ".join(f"{a:g}-{b:g} deg" for a, b in zip(
        SUN_ZENITH_EDGES_DEG[:-1], SUN_ZENITH_EDGES_DEG[1:], strict=True)) + " |")
    print("|---" * SUN_ZENITH_EDGES_DEG.size + "|")
    for i in range(ALTITUDE_EDGES_M.size - 1):
        h = 0.5 * (ALTITUDE_EDGES_M[i] + ALTITUDE_EDGES_M[i + 1])
        cells = []
        for j in range(SUN_ZENITH_EDGES_DEG.size - 1):
            zenith = np.radians(0.5 * (SUN_ZENITH_EDGES_DEG[j] + SUN_ZENITH_EDGES_DEG[j + 1]))
            cells.append(f"{ratio[i, j]:.3f} \\| {spread.beam_at(h, np.cos(zenith))[w]:.3f}")
        print(f"| {ALTITUDE_EDGES_M[i] / 1e3:g}-{ALTITUDE_EDGES_M[i + 1] / 1e3:g} km | "
              + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
