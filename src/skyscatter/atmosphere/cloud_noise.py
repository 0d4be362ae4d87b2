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
so the texture is the same on every machine. `sample_texture` reads it trilinearly with
wrap-around at texel coordinates.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit, prange

from skyscatter.checks import checked_integer

__all__ = ["NOISE_TEXTURE_SIZE", "hash32", "noise_texture", "sample_texture"]

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


@njit(cache=True, inline="always")
def _cell_hash(i, j, k, period, seed, salt):
    """Hash of the lattice cell (i, j, k) modulo `period`, for `seed` and `salt`."""
    h = hash32(np.uint64(seed) ^ np.uint64((salt * 0x9E3779B9) & 0xFFFFFFFF))
    h = hash32(h ^ np.uint64(i % period))
    h = hash32(h ^ np.uint64(j % period))
    return hash32(h ^ np.uint64(k % period))


@njit(cache=True, inline="always")
def _unit(h: np.uint32) -> float:
    return float(h) / 4294967296.0


@njit(cache=True, inline="always")
def _fade(t: float) -> float:
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


@njit(cache=True)
def _gradient_dot(i, j, k, period, seed, salt, dx, dy, dz):
    """Dot product of the cell corner's pseudo-random unit gradient with the offset."""
    h = _cell_hash(i, j, k, period, seed, salt)
    z = 2.0 * _unit(h) - 1.0
    phi = 2.0 * np.pi * _unit(hash32(h))
    s = np.sqrt(max(0.0, 1.0 - z * z))
    return s * np.cos(phi) * dx + s * np.sin(phi) * dy + z * dz


@njit(cache=True)
def _perlin(x, y, z, period, seed, salt):
    """Periodic gradient noise at lattice coordinates (x, y, z), period `period` cells;
    roughly in [-1, 1]."""
    i0, j0, k0 = int(np.floor(x)), int(np.floor(y)), int(np.floor(z))
    fx, fy, fz = x - i0, y - j0, z - k0
    u, v, w = _fade(fx), _fade(fy), _fade(fz)
    total = 0.0
    for a in range(2):
        wa = u if a else 1.0 - u
        for b in range(2):
            wb = v if b else 1.0 - v
            for c in range(2):
                wc = w if c else 1.0 - w
                total += wa * wb * wc * _gradient_dot(i0 + a, j0 + b, k0 + c, period, seed,
                                                      salt, fx - a, fy - b, fz - c)
    return total


@njit(cache=True)
def _worley(x, y, z, period, seed, salt):
    """Periodic cellular noise: distance to the nearest feature point (one per cell), in
    cells, at lattice coordinates (x, y, z); 0 at a feature point, ~1 at most."""
    i0, j0, k0 = int(np.floor(x)), int(np.floor(y)), int(np.floor(z))
    nearest = 3.0
    for a in range(-1, 2):
        for b in range(-1, 2):
            for c in range(-1, 2):
                h = _cell_hash(i0 + a, j0 + b, k0 + c, period, seed, salt)
                h2 = hash32(h)
                px = i0 + a + _unit(h)
                py = j0 + b + _unit(h2)
                pz = k0 + c + _unit(hash32(h2))
                d = np.sqrt((px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2)
                nearest = min(nearest, d)
    return min(nearest, 1.0)


@njit(cache=True)
def _worley_fbm(x, y, z, cells, seed, salt):
    """Inverted Worley noise summed over octaves (weights 0.625, 0.25, 0.125), in [0, 1]."""
    total = 0.0
    weight_sum = 0.0
    weight = 0.625
    for octave in range(_WORLEY_OCTAVES):
        scale = cells * (1 << octave)
        total += weight * (1.0 - _worley(x * scale, y * scale, z * scale, scale, seed,
                                         salt + octave))
        weight_sum += weight
        weight = 0.25 if octave == 0 else weight * 0.5
    return total / weight_sum


@njit(cache=True, parallel=True)
def _bake(n, seed, out):
    """Shape (before equalisation) and detail channels at the texel centres of a tile."""
    for i in prange(n):
        for j in range(n):
            for k in range(n):
                x, y, z = (i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n
                perlin = 0.0
                amplitude = 1.0
                for octave in range(_PERLIN_OCTAVES):
                    cells = _BASE_CELLS << octave
                    perlin += amplitude * _perlin(x * cells, y * cells, z * cells, cells, seed,
                                                  octave)
                    amplitude *= 0.5
                perlin = min(max(0.5 + 0.5 * perlin, 0.0), 1.0)
                worley = _worley_fbm(x, y, z, _BASE_CELLS, seed, 16)
                # Perlin-Worley: the Perlin field remapped from [worley - 1, 1] to [0, 1]
                out[i, j, k, 0] = (perlin - (worley - 1.0)) / (2.0 - worley)
                out[i, j, k, 1] = _worley_fbm(x, y, z, _DETAIL_CELLS, seed, 32)


@lru_cache(maxsize=4)
def noise_texture(seed: int, size: int = NOISE_TEXTURE_SIZE) -> np.ndarray:
    """The (size, size, size, 2) float32 tile of `seed` (module docstring), read-only:
    channel 0 the equalised shape, channel 1 the detail, both in [0, 1]."""
    seed = checked_integer("seed", seed, 0, 2**32 - 1)
    size = checked_integer("size", size, 8, 512)
    texture = np.empty((size, size, size, 2), dtype=np.float64)
    _bake(size, seed, texture)
    shape = texture[..., 0].reshape(-1)
    ranks = np.empty(shape.size)
    ranks[np.argsort(shape, kind="stable")] = (np.arange(shape.size) + 0.5) / shape.size
    texture[..., 0] = ranks.reshape(texture.shape[:3])
    result = texture.astype(np.float32)
    result.flags.writeable = False
    return result


@njit(cache=True, inline="always")
def sample_texture(texture, channel, x, y, z):
    """Trilinear sample of `texture[..., channel]` at texel coordinates (x, y, z), wrapping
    around (texel centres at i + 0.5)."""
    n = texture.shape[0]
    x -= 0.5
    y -= 0.5
    z -= 0.5
    fx, fy, fz = np.floor(x), np.floor(y), np.floor(z)
    tx, ty, tz = x - fx, y - fy, z - fz
    i0, j0, k0 = int(fx) % n, int(fy) % n, int(fz) % n
    i1, j1, k1 = (i0 + 1) % n, (j0 + 1) % n, (k0 + 1) % n
    c00 = texture[i0, j0, k0, channel] * (1 - tz) + texture[i0, j0, k1, channel] * tz
    c01 = texture[i0, j1, k0, channel] * (1 - tz) + texture[i0, j1, k1, channel] * tz
    c10 = texture[i1, j0, k0, channel] * (1 - tz) + texture[i1, j0, k1, channel] * tz
    c11 = texture[i1, j1, k0, channel] * (1 - tz) + texture[i1, j1, k1, channel] * tz
    return ((c00 * (1 - ty) + c01 * ty) * (1 - tx)) + ((c10 * (1 - ty) + c11 * ty) * tx)
