"""Benchmark: all 117 955 Hipparcos stars into a 1024x1024 fisheye on 16 wavelengths.

Steps timed (best of 5 after a warm-up; wall and process CPU time, peak traced memory):
catalogue load (in-memory cache hit), proper motion to 2024.0, `stellar_irradiance` of every
star on the 16-bin 360–830 nm grid, `add_stars` of all stars with a random ENU rotation (about
half are above the horizon), and `integrated_starlight_radiance` for 1M directions. The first,
uncached catalogue parse is reported separately. On a machine shared with other work the CPU
time says more than the wall time.

Run: PYTHONPATH=src python benchmarks/bench_stars.py
"""

from __future__ import annotations

import time

import numpy as np
from timing import best_of

from skyscatter.astro import star_catalogue
from skyscatter.render.camera import FisheyeCamera
from skyscatter.render.stars import add_stars, integrated_starlight_radiance
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.spectrum.magnitudes import colour_temperature_from_b_minus_v, stellar_irradiance

SIZE = 1024


def main() -> None:
    start = time.perf_counter()
    parsed = star_catalogue._parse_hip2(star_catalogue._catalogue_path())
    print(f"parse hip2.dat ({parsed['hip'].size} stars): {time.perf_counter() - start:.3f} s")
    catalogue = star_catalogue.load_star_catalogue()
    wavelengths = wavelength_grid(DEFAULT_WAVELENGTH_BINS)
    camera = FisheyeCamera(SIZE)
    valid = camera.valid_mask()
    rotation, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))
    directions = catalogue.directions_at(2024.0) @ rotation.T
    temperature = colour_temperature_from_b_minus_v(catalogue.b_minus_v)
    irradiance = stellar_irradiance(catalogue.v_magnitude, temperature, wavelengths)
    image = np.zeros((SIZE, SIZE, wavelengths.size))
    transmittance = np.full((len(catalogue), wavelengths.size), 0.8)
    rng = np.random.default_rng(2)
    sky = rng.normal(size=(1_000_000, 3))

    steps = {
        "load_star_catalogue (memory cache)": star_catalogue.load_star_catalogue,
        "directions_at(2024.0)": lambda: catalogue.directions_at(2024.0),
        "stellar_irradiance, 16 wl": lambda: stellar_irradiance(
            catalogue.v_magnitude, colour_temperature_from_b_minus_v(catalogue.b_minus_v),
            wavelengths),
        f"add_stars, {SIZE}^2 fisheye": lambda: add_stars(
            image, camera, valid, directions, irradiance, transmittance=transmittance),
        "integrated_starlight_radiance, 1M dirs": lambda: integrated_starlight_radiance(
            sky, wavelengths, 6.0),
    }
    print(f"stars above the horizon: {int(np.sum(directions[:, 2] > 0.0))} of {len(catalogue)}")
    for name, function in steps.items():
        wall, cpu, peak = best_of(function, repeats=5, warm_up=True)
        print(f"{name:42s} wall {wall:.3f} s  cpu {cpu:.3f} s  peak {peak:7.1f} MiB")


if __name__ == "__main__":
    main()
