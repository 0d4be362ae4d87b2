"""What an image, a radiance table or a time-lapse will cost, estimated before any work starts.

Memory. An image of w x h pixels on n_wl wavelengths peaks at about

    w h (32 n_wl + 512) bytes

over what the tables hold. Measured (growth of the peak resident memory during `api.render`,
earth preset, 2-order tables loaded beforehand, 2-core machine): lut solver, perspective
1024 x 1024: 371 B per pixel at 16 wavelengths, 170 B at 4; fisheye 1000 x 1000: 289 B at 16;
single solver, perspective 1024 x 512: 820 B at 16 (its ray-marching buffers). The estimate is
1024 B at 16 wavelengths, 25 % over the largest of them. A radiance table holds one Python
dict per row (seven floats: about 700 B); 1024 B per row is counted. The limit is this
computer's physical memory: past it the job would swap or be killed.

Time. The ray-marching ("single") and Monte Carlo solvers cost view rays x samples x
wavelengths; measured on 2 cores (`api.sky_radiance_rows`, earth): 3.6e6 of these per second
for "single", 8e4 paths per second for "montecarlo". A job estimated at more than an hour is
refused. The table solver ("lut") does not use samples.

`allow_large=True` (the CLI's --allow-large) lifts both limits. Time-lapses are capped at
`MAX_FRAMES` frames and samples at `MAX_SAMPLES` per ray, whatever the override.

Public names: `check_cost`, `image_memory_bytes`, `memory_limit_bytes`, `MAX_FRAMES`,
`MAX_SAMPLES`.
"""

from __future__ import annotations

import os

from skyscatter.errors import InputError

__all__ = ["MAX_FRAMES", "MAX_SAMPLES", "check_cost", "image_memory_bytes", "memory_limit_bytes"]

BYTES_PER_PIXEL_WAVELENGTH = 32  # B: four float64 spectral arrays per pixel (measured above)
BYTES_PER_PIXEL = 512  # B: directions, masks, colour and display arrays per pixel
BYTES_PER_ROW = 1024  # B per radiance row (a dict of seven floats, about 700 B)
SAMPLES_PER_SECOND = {"single": 3.6e6, "montecarlo": 8.0e4}  # rays x samples x wl / s, 2 cores
MAX_SECONDS = 3600.0  # s: an hour of computing
MAX_FRAMES = 100_000  # frames of one time-lapse (69 days at one frame a minute)
MAX_SAMPLES = 10**9  # samples per ray: beyond any use, and within the kernels' integers
_GIB = 2.0**30
_OVERRIDE = "or pass --allow-large (Python: allow_large=True) to run it anyway"


def image_memory_bytes(width: int, height: int, n_wavelengths: int) -> float:
    """Estimated peak memory [B] of rendering a `width` x `height` image on `n_wavelengths`."""
    return float(width) * float(height) * (BYTES_PER_PIXEL_WAVELENGTH * n_wavelengths
                                           + BYTES_PER_PIXEL)


def memory_limit_bytes() -> float:
    """This computer's physical memory [B] (infinite where the system does not say)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE")) * float(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return float("inf")


def _gib(size_bytes: float) -> str:
    gib = size_bytes / _GIB
    return f"{gib:.3g}" if gib < 1000.0 else f"{gib:,.0f}"


def check_cost(what: str, memory_bytes: float, rays: float, n_wavelengths: int, *,
               solver: str, n_samples: int, allow_large: bool = False) -> None:
    """InputError naming `what` (e.g. "a 512 x 512-pixel image at 16 wavelengths") when it
    would need more memory than this computer has, or (solvers "single" and "montecarlo")
    more than an hour for `rays` view rays x `n_samples` x `n_wavelengths`; nothing when
    `allow_large`."""
    if allow_large:
        return
    limit = memory_limit_bytes()
    if memory_bytes > limit:
        raise InputError(
            f"{what} would need about {_gib(memory_bytes)} GiB of memory, more than the "
            f"{_gib(limit)} GiB of this computer; make it smaller, {_OVERRIDE}",
            key="memory", value=memory_bytes, allowed=f"<= {_gib(limit)} GiB")
    rate = SAMPLES_PER_SECOND.get(solver)
    if rate is None:
        return
    seconds = float(rays) * float(n_samples) * float(n_wavelengths) / rate
    if seconds > MAX_SECONDS:
        raise InputError(
            f"{what} with {n_samples} samples per ray and the {solver} solver would take about "
            f"{seconds / 3600.0:.3g} hours ({rate:.2g} ray samples per second on 2 cores), more "
            f"than the limit of {MAX_SECONDS / 3600.0:.0f} hour; use fewer samples, rays or "
            f"wavelengths, {_OVERRIDE}", key="samples", value=n_samples,
            allowed=f"<= {MAX_SECONDS / 3600.0:.0f} hour")
