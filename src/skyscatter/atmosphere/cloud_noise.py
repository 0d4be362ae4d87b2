"""A tileable 3D noise texture for cloud shapes, reproducible from a seed.

Two channels on an n x n x n periodic lattice (`noise_texture`), the pair that real-time
volumetric clouds are modelled from (Schneider & Vos 2015, "The real-time volumetric
cloudscapes of Horizon Zero Dawn", SIGGRAPH Advances in Real-Time Rendering; Hillaire 2016,
"Physically based sky, atmosphere and cloud rendering in Frostbite", SIGGRAPH course):

- shape: Perlin's gradient noise (Perlin 2002, "Improving noise", ACM TOG 21, 681,
  doi:10.1145/566654.566636; quintic fade) in 4 octaves, its valleys carved by inverted
  Worley cellular noise (Worley 1996, SIGGRAPH, doi:10.1145/237170.237267) in 3 octaves:
  billowy, cauliflower-like blobs. The channel is then equalised to a uniform distribution
  on [0, 1] (its rank among all texels), so that keeping the texels above 1 - c keeps exactly
  the fraction c of the volume: a layer's `coverage` is a fraction of the sky, not a knob.
- detail: inverted Worley noise in 3 octaves at 4 times the frequency, which erodes the edges.

Every lattice gradient and Worley feature point comes from an integer hash of its (periodic)
cell and the seed (the "lowbias32" mixer, Wellons 2018, https://nullprogram.com/blog/2018/07/31/),
so the texture is the same on every machine. `atmosphere._cloud_sampling.sample_texture`
reads it trilinearly with wrap-around at texel coordinates.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit, prange

from skyscatter.checks import checked_integer
from skyscatter.errors import InputError

__all__ = ["NOISE_TEXTURE_SIZE", "hash32", "noise_texture"]

NOISE_TEXTURE_SIZE = 128  # texels per side: 8 MiB of float32 x 2 channels; baked in ~1 s
_PERLIN_OCTAVES = 4
_WORLEY_OCTAVES = 3
_BASE_CELLS = 4  # lattice cells per tile of the lowest octave (shape channel)
_DETAIL_CELLS = 16  # Worley cells per tile of the detail channel's lowest octave


_MASK = np.uint64(0xFFFFFFFF)


@njit(cache=True, inline="always")
def hash32(x):
    """lowbias32 (Wellons 2018): a 32-bit integer mixer with low bias (uint64 arithmetic,
    masked to 32 bits: numba widens products of uint32)."""
    x = np.uint64(x) & _MASK
    x ^= x >> np.uint64(16)
    x = (x * np.uint64(0x7FEB352D)) & _MASK
    x ^= x >> np.uint64(15)
    x = (x * np.uint64(0x846CA68B)) & _MASK
    x ^= x >> np.uint64(16)
    return x


@njit(cache=True)
def _lattice(period, seed, salt):
    """Three uniform numbers in [0, 1) per cell of a periodic lattice (period, period,
    period, 3), from hashes of the cell, `seed` and `salt`."""
    out = np.empty((period, period, period, 3))
    base = hash32(np.uint64(seed) ^ np.uint64((salt * 0x9E3779B9) & 0xFFFFFFFF))
    for i in range(period):
        for j in range(period):
            for k in range(period):
                h = hash32(hash32(hash32(base ^ np.uint64(i)) ^ np.uint64(j)) ^ np.uint64(k))
                for c in range(3):
                    out[i, j, k, c] = float(h) / 4294967296.0
                    h = hash32(h)
    return out


def _gradients(period: int, seed: int, salt: int) -> np.ndarray:
    """Unit gradient vectors (period, period, period, 3), uniform on the sphere."""
    u = _lattice(period, seed, salt)
    z = 2.0 * u[..., 0] - 1.0
    phi = 2.0 * np.pi * u[..., 1]
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


@njit(cache=True, inline="always")
def _fade(t):
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


@njit(cache=True, parallel=True)
def _add_perlin(n, gradients, amplitude, out):
    """out (n, n, n) += amplitude x periodic gradient noise (Perlin 2002) of the lattice of
    `gradients` over the tile, at the texel centres; roughly in [-1, 1]."""
    period = gradients.shape[0]
    for i in prange(n):
        for j in range(n):
            for k in range(n):
                x, y, z = (i + 0.5) / n * period, (j + 0.5) / n * period, (k + 0.5) / n * period
                i0, j0, k0 = int(x), int(y), int(z)
                fx, fy, fz = x - i0, y - j0, z - k0
                u, v, w = _fade(fx), _fade(fy), _fade(fz)
                total = 0.0
                for a in range(2):
                    wa = u if a else 1.0 - u
                    for b in range(2):
                        wb = v if b else 1.0 - v
                        for c in range(2):
                            wc = w if c else 1.0 - w
                            g = gradients[(i0 + a) % period, (j0 + b) % period,
                                          (k0 + c) % period]
                            total += wa * wb * wc * (g[0] * (fx - a) + g[1] * (fy - b)
                                                     + g[2] * (fz - c))
                out[i, j, k] += amplitude * total


@njit(cache=True, parallel=True)
def _add_inverted_worley(n, features, weight, out):
    """out (n, n, n) += weight x (1 - F1), F1 the distance [cells] to the nearest feature
    point (one per cell at the offsets `features`; Worley 1996), capped at 1, at the texel
    centres of the periodic tile."""
    period = features.shape[0]
    for i in prange(n):
        for j in range(n):
            for k in range(n):
                x, y, z = (i + 0.5) / n * period, (j + 0.5) / n * period, (k + 0.5) / n * period
                i0, j0, k0 = int(x), int(y), int(z)
                nearest = 1.0
                for a in range(-1, 2):
                    for b in range(-1, 2):
                        for c in range(-1, 2):
                            f = features[(i0 + a) % period, (j0 + b) % period,
                                         (k0 + c) % period]
                            d2 = ((i0 + a + f[0] - x) ** 2 + (j0 + b + f[1] - y) ** 2
                                  + (k0 + c + f[2] - z) ** 2)
                            nearest = min(nearest, d2)
                out[i, j, k] += weight * (1.0 - np.sqrt(nearest))


def _worley_fbm(n: int, cells: int, seed: int, salt: int) -> np.ndarray:
    """Inverted Worley noise over `_WORLEY_OCTAVES` octaves from `cells` cells per tile
    (weights 0.625, 0.25, 0.125, normalised), in [0, 1]."""
    out = np.zeros((n, n, n))
    weights = (0.625, 0.25, 0.125)[:_WORLEY_OCTAVES]
    for octave, weight in enumerate(weights):
        _add_inverted_worley(n, _lattice(cells << octave, seed, salt + octave),
                             weight / sum(weights), out)
    return out


def _bake(n: int, seed: int) -> np.ndarray:
    """Shape (before equalisation) and detail channels (n, n, n, 2) at the texel centres."""
    perlin = np.zeros((n, n, n))
    for octave in range(_PERLIN_OCTAVES):
        _add_perlin(n, _gradients(_BASE_CELLS << octave, seed, octave), 0.5**octave, perlin)
    perlin = np.clip(0.5 + 0.5 * perlin, 0.0, 1.0)
    worley = _worley_fbm(n, _BASE_CELLS, seed, 16)
    # Perlin-Worley: the Perlin field remapped from [worley - 1, 1] to [0, 1]
    shape = (perlin - (worley - 1.0)) / (2.0 - worley)
    return np.stack([shape, _worley_fbm(n, _DETAIL_CELLS, seed, 32)], axis=-1)


@lru_cache(maxsize=4)
def noise_texture(seed: int, size: int = NOISE_TEXTURE_SIZE) -> np.ndarray:
    """The (size, size, size, 2) float32 tile of `seed` (module docstring), read-only:
    channel 0 the equalised shape, channel 1 the detail, both in [0, 1]."""
    seed = checked_integer("seed", seed, 0, 2**32 - 1)
    size = checked_integer("size", size, 8, 512)
    if size & (size - 1):
        raise InputError(f"noise texture size {size} must be a power of two", key="size",
                         value=size, allowed="8, 16, ..., 512")
    texture = _bake(size, seed)
    shape = texture[..., 0].reshape(-1)
    ranks = np.empty(shape.size)
    ranks[np.argsort(shape, kind="stable")] = (np.arange(shape.size) + 0.5) / shape.size
    texture[..., 0] = ranks.reshape(texture.shape[:3])
    result = texture.astype(np.float32)
    result.flags.writeable = False
    return result
