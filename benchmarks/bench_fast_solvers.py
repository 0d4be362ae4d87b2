"""Benchmark: the fast solvers' precomputation, one observer's tables and a 1920 x 1080 frame on
the CPU, earth preset, 16 wavelengths. Prints a table of wall time (best of 3 after a JIT
warm-up; the full render once) and peak traced memory (tracemalloc: numpy and Python
allocations), then the process's peak resident memory.

Run: python benchmarks/bench_fast_solvers.py   (docs/techniques.md quotes its output)
"""

from __future__ import annotations

import resource

import numba
import numpy as np
from timing import best_of

from skyscatter import api
from skyscatter.render.camera import EquirectangularCamera
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport import hillaire
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.hillaire import HillaireSolver
from skyscatter.transport.single_scattering import observer_position

WIDTH, HEIGHT = 1920, 1080


def hillaire_rows(profile, directions: np.ndarray, sun: np.ndarray) -> list[tuple]:
    """(step, seconds, peak MiB) of the Hillaire 2020 solver."""
    origin = observer_position(0.0, profile.bottom_radius_m)
    solver = HillaireSolver(profile)
    rows = [("hillaire: transmittance + multiple-scattering tables",
             *best_of(lambda: HillaireSolver(profile), warm_up=True)[::2]),
            ("hillaire: sky-view table, one observer",
             *best_of(lambda: solver.sky_view_table(origin, sun), warm_up=True)[::2]),
            (f"hillaire: sky_radiance, {WIDTH}x{HEIGHT} rays (sky-view table)",
             *best_of(lambda: solver.sky_radiance(origin, directions, sun), warm_up=True)[::2])]
    marched = directions[:hillaire.SKY_VIEW_MIN_RAYS - 1]  # below the table's threshold
    seconds, _, peak = best_of(lambda: solver.sky_radiance(origin, marched, sun), warm_up=True)
    rows.append((f"hillaire: every ray marched, scaled to {WIDTH}x{HEIGHT}",
                 seconds * directions.shape[0] / marched.shape[0], peak))
    return rows


def render_row(atmosphere, solver: str, wavelengths: np.ndarray) -> tuple:
    """(step, seconds, peak MiB) of `api.render` of the whole frame (panorama, sun 45 deg)."""
    camera = EquirectangularCamera(WIDTH, HEIGHT)

    def render() -> None:
        api.render(atmosphere, camera, 45.0, wavelengths_nm=wavelengths, solver=solver)

    api.render(atmosphere, EquirectangularCamera(64, 32), 45.0, wavelengths_nm=wavelengths,
               solver=solver)  # JIT warm-up
    seconds, _, peak = best_of(render, repeats=1)
    return (f"{solver}: api.render {WIDTH}x{HEIGHT} panorama (all steps)", seconds, peak)


def main() -> None:
    atmosphere = api.load_atmosphere("earth")
    wavelengths = wavelength_grid(DEFAULT_WAVELENGTH_BINS)
    profile = atmosphere.optical_profile(wavelengths)
    directions, _ = EquirectangularCamera(WIDTH, HEIGHT).directions()
    directions = np.ascontiguousarray(directions.reshape(-1, 3))
    sun = local_frame_directions(np.radians(45.0), np.pi)
    print(f"numba threads: {numba.get_num_threads()}, earth preset, "
          f"{wavelengths.size} wavelengths")
    rows = hillaire_rows(profile, directions, sun) + [render_row(atmosphere, "hillaire",
                                                                 wavelengths)]
    width = max(len(row[0]) for row in rows)
    print(f"{'step':<{width}}  {'wall [s]':>9}  {'peak [MiB]':>10}")
    for step, seconds, peak in rows:
        print(f"{step:<{width}}  {seconds:9.3f}  {peak:10.1f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
