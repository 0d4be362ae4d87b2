"""Cloud shadows on surfaces seen from afar: the independent column approximation.

A layer's tile is far below a pixel of a view from space (`atmosphere.cloud_field`, "Whole-
planet clouds"); the sunlight reaching a ground point behind such a pixel, marched through
the noise at that one point (`transport.clouds.cloud_transmittance`), is 1 or a cloud's
shadow at random from pixel to pixel: speckle. The pixel's mean over its footprint, in the
independent column approximation (Cahalan et al. 1994, J. Atmos. Sci. 51, 2434,
doi:10.1175/1520-0469(1994)051<2434:TAOFSC>2.0.CO;2) that the renderer's far field uses
(`transport._cloud_kernels._cross_columns`), is for each layer l

    T_l = 1 - c_col (1 - <exp(-k_ext W_b L / H)>)

with c_col the layer's cloudy column fraction and W_b the mean water paths of its shares of
cloudy columns (`_cloud_sampling.COLUMN_SHARES`; <> the mean weighted by the shares) at the
coverage map's value where the sun ray crosses it, L the ray's chord through the layer's
shell and H its thickness; layers multiply (their columns overlap at random). Between the
layer's `FAR_START` and `FAR_END` (distances from the camera) it blends smoothly with the
marched transmittance, as the view rays do.

With `diffuse` the light a cloud passes on scattered counts too, as the renderer's
conservative two-stream slab has it (`transport._two_stream`; the clouds' shadows in the
air, `transport.air_shadows`): a water path W towards the sun lets through the share
C = (1 + e + 1.5 mu_s (1 - e)) / (2 (1 + gamma k_ext W mu_s)) of the sunlight on the
horizontal, directly or scattered (e = exp(-k_ext W), gamma = 3 (1 - g) / 4, mu_s the sun's
zenith cosine at the point), in place of exp(-k_ext W) in both forms.
"""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere._cloud_sampling import (
    BASE_R,
    COLUMN_BINS,
    COLUMN_NODES,
    COLUMN_SHARES,
    COLUMN_VALUES,
    FAR_END,
    FAR_START,
    TOP_R,
    coverage_map_factors,
)
from skyscatter.atmosphere.cloud_config import MAX_PROFILE_NODES
from skyscatter.atmosphere.cloud_field import CloudField
from skyscatter.transport import _cloud_kernels, _two_stream

__all__ = ["diffuse_passed", "sunlight_passed", "surface_cloud_transmittance"]


def surface_cloud_transmittance(field: CloudField, camera: np.ndarray, points: np.ndarray,
                                sun: np.ndarray, *, diffuse: bool = False) -> np.ndarray:
    """Transmittance [-] (n, n_wl) of the clouds towards the unit `sun` (3,) from surface
    `points` (n, 3) [m] seen from `camera` (3,) [m] (module docstring): marched near the
    camera, the independent columns' mean far from it; with `diffuse` the share of the
    sunlight that reaches the points directly or scattered by the clouds."""
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    sun = np.asarray(sun, dtype=np.float64)
    n = points.shape[0]
    mu_s = np.maximum(points @ sun / np.linalg.norm(points, axis=1), 0.0) if diffuse else None
    directions = np.ascontiguousarray(np.broadcast_to(sun, (n, 3)))
    water = np.empty((n, field.n_layers))
    _cloud_kernels.cloud_water_paths(points, directions, np.full(n, np.inf),
                                     field.bottom_radius_m, field.params, field.profiles,
                                     field.textures, water)
    distance = np.linalg.norm(points - np.asarray(camera, dtype=np.float64), axis=1)
    result = np.ones((n, field.wavelengths_nm.size))
    for layer in range(field.n_layers):
        row = field.params[layer]
        marched = _passed(field, layer, water[:, layer], mu_s)
        span = row[FAR_END] - row[FAR_START]
        f = np.clip((distance - row[FAR_START]) / span, 0.0, 1.0) if span > 0 else (
            (distance > row[FAR_START]).astype(np.float64))
        f = f * f * (3.0 - 2.0 * f)
        far = f > 0.0
        transmittance = marched
        if np.any(far):
            columns = _column_transmittance(field, layer, points[far], sun,
                                            None if mu_s is None else mu_s[far])
            transmittance = marched.copy()
            transmittance[far] = (f[far, None] * columns
                                  + (1.0 - f[far, None]) * marched[far])
        result *= transmittance
    return result


def sunlight_passed(field: CloudField, layer: int, paths: np.ndarray,
                    mu_s: np.ndarray) -> np.ndarray:
    """(..., n_wl): the share of the sunlight on the horizontal that a conservative two-stream
    slab of `layer`'s water lets through, directly or scattered (module docstring), for the
    water paths W (...) [g m^-2] towards the sun at zenith cosines `mu_s` (...)."""
    depth = np.asarray(paths)[..., None] * field.mass_extinction_m2_g[layer]
    mu = np.asarray(mu_s, dtype=np.float64)[..., None]
    gamma = _two_stream.EDDINGTON * (1.0 - field.asymmetry[layer])
    return _two_stream.beam_passed(gamma * depth * mu, np.exp(-depth), mu)


def diffuse_passed(field: CloudField, layer: int, paths: np.ndarray) -> np.ndarray:
    """(..., n_wl): the share of a diffuse flux that a conservative two-stream slab of
    `layer`'s vertical water paths W (...) [g m^-2] lets through, 1 / (1 + gamma k_ext W)."""
    depth = np.asarray(paths)[..., None] * field.mass_extinction_m2_g[layer]
    return _two_stream.diffuse_passed(_two_stream.EDDINGTON * (1.0 - field.asymmetry[layer])
                                      * depth)


def _passed(field: CloudField, layer: int, paths: np.ndarray,
            mu_s: np.ndarray | None) -> np.ndarray:
    """(n, n_wl): exp(-k_ext W) of `layer` for the water paths W (n,) towards the sun, or with
    the sun's zenith cosines `mu_s` (n,) the two-stream's share (`sunlight_passed`)."""
    if mu_s is None:
        return np.exp(-paths[:, None] * field.mass_extinction_m2_g[layer])
    return sunlight_passed(field, layer, paths, mu_s)


def _column_transmittance(field: CloudField, layer: int, points: np.ndarray,
                          sun: np.ndarray, mu_s: np.ndarray | None) -> np.ndarray:
    """1 - c_col (1 - <exp(-k_ext W_b L / H)>) (n, n_wl) of `layer` (module docstring; with
    `mu_s`, the two-stream's share in place of exp)."""
    row = field.params[layer]
    base, top = row[BASE_R], row[TOP_R]
    b = points @ sun
    c = np.einsum("ij,ij->i", points, points)

    def exits(radius: float) -> np.ndarray:  # the farther root, 0 if the line misses
        disc = b * b - c + radius * radius
        return np.where(disc > 0.0, -b + np.sqrt(np.maximum(disc, 0.0)), 0.0)

    t_base = np.where(c < base * base, exits(base), 0.0)
    t_top = exits(top)
    chord = np.maximum(t_top - np.maximum(t_base, 0.0), 0.0)
    # below the horizon of the shell the ray crosses it twice; the sun is set there anyway
    middle = points + (0.5 * (np.maximum(t_base, 0.0) + t_top))[:, None] * sun
    factors = np.empty(points.shape[0])
    coverage_map_factors(field.params, field.profiles, layer, np.ascontiguousarray(middle),
                         factors)
    rows = COLUMN_NODES * COLUMN_VALUES // 2
    table = field.profiles[layer, MAX_PROFILE_NODES:MAX_PROFILE_NODES + rows].reshape(
        COLUMN_NODES, COLUMN_VALUES)
    nodes = np.linspace(0.0, 1.0, COLUMN_NODES)
    m = np.clip(factors, 0.0, 1.0)
    cover = np.interp(m, nodes, table[:, 0])
    cloudy = np.zeros((points.shape[0], field.wavelengths_nm.size))
    for b in range(COLUMN_BINS):
        slant = np.interp(m, nodes, table[:, 1 + b]) * chord / (top - base)
        cloudy += _passed(field, layer, slant, mu_s) * COLUMN_SHARES[b]
    return 1.0 - cover[:, None] * (1.0 - cloudy)
