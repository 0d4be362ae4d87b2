"""The water content of cloud layers at any point of a planet, for the kernels that march it.

`cloud_field` turns `Clouds` (`atmosphere.cloud_config`) into arrays: per layer its shell, the
parameters of its shape, its noise tile (`atmosphere.cloud_noise`), and its optics per gram of
water on the render's wavelengths (`optics.cloud_optics`). `layer_water` is the one definition
of the water content w(p) [g m^-3] that the renderer and the Monte Carlo reference both read:

    h   = (|p| - r_base) / (r_top - r_base)                  height fraction in the layer
    q   = S (p - u t) / scale                                 tile coordinates (world frame)
    c   = coverage f(h) (1 + v (2 n(q / 7.31) - 1))           local coverage: the profile f
                                                              narrows the tops, v varies it
    d0  = clamp((n(q) - (1 - c)) / (e c), 0, 1)               n: the equalised shape noise,
                                                              e: the edge ramp
    d   = clamp((d0 - s m(q')) / (1 - s m(q')), 0, 1)         m: detail noise on its own tile,
                                                              s: detail_strength
    w   = water_content d

with u the wind (east, north in the observer's frame) and t the time, and S a stretch by
1 / `stretch` along the wind. Since n is uniform on [0, 1], a flat layer (f = 1, v = 0) has
d0 > 0 on exactly the fraction c of its volume (the edges and erosion then trim it).
A "sheet" layer is the same field with the height fraction fixed at 0.5: its water content
does not vary through its thickness.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from skyscatter.atmosphere.cloud_config import MAX_PROFILE_NODES, CloudLayer, Clouds
from skyscatter.atmosphere.cloud_noise import NOISE_TEXTURE_SIZE, noise_texture, sample_texture
from skyscatter.checks import checked_number
from skyscatter.optics.cloud_optics import CloudOptics, ice_cloud_optics, liquid_cloud_optics

__all__ = [
    "PHASE_ANGLES",
    "CloudField",
    "cloud_field",
    "layer_water",
    "phase_table_index",
]

PHASE_ANGLES = 1024  # phase table nodes, theta = pi (i / (n - 1))^2: 0.0017 deg steps at 0
COVERAGE_TILE_RATIO = 7.31  # the coverage varies on tiles this much larger (no common period)

# Columns of `CloudField.params`
BASE_R, TOP_R, COVERAGE, WATER, INV_SCALE, INV_DETAIL_SCALE, DETAIL = 0, 1, 2, 3, 4, 5, 6
EDGE, VARIATION, SHEET, N_PROFILE, OFFSET_X, OFFSET_Y, OFFSET_Z = 7, 8, 9, 10, 11, 12, 13
ALONG_X, ALONG_Y, ALONG_Z, STRETCH_MINUS_ONE = 14, 15, 16, 17
N_PARAMS = 18


@dataclass(frozen=True, eq=False)
class CloudField:
    """Arrays of cloud layers for the kernels (module docstring); layers lowest first.

    params (n_layers, N_PARAMS); profiles (n_layers, MAX_PROFILE_NODES, 2); textures
    (n_layers, n, n, n, 2) float32; mass_extinction_m2_g, single_scattering_albedo and
    asymmetry (n_layers, n_wl); phase (n_layers, PHASE_ANGLES, n_wl) [sr^-1] at
    theta = pi (i / (PHASE_ANGLES - 1))^2.
    """

    clouds: Clouds
    bottom_radius_m: float
    wavelengths_nm: np.ndarray
    params: np.ndarray
    profiles: np.ndarray
    textures: np.ndarray
    mass_extinction_m2_g: np.ndarray
    single_scattering_albedo: np.ndarray
    asymmetry: np.ndarray
    phase: np.ndarray

    @property
    def n_layers(self) -> int:
        return self.params.shape[0]

    @property
    def lowest_radius_m(self) -> float:
        return float(self.params[:, BASE_R].min())

    @property
    def highest_radius_m(self) -> float:
        return float(self.params[:, TOP_R].max())


def layer_optics(layer: CloudLayer, wavelengths_nm: np.ndarray) -> CloudOptics:
    """The layer's particle optics on `wavelengths_nm` [nm] (`optics.cloud_optics`)."""
    particles = layer.particles
    if particles.phase == "ice":
        return ice_cloud_optics(particles.effective_radius_um, wavelengths_nm)
    return liquid_cloud_optics(particles.effective_radius_um, particles.effective_variance,
                               wavelengths_nm)


def cloud_field(clouds: Clouds, bottom_radius_m: float, wavelengths_nm: np.ndarray, *,
                to_world: np.ndarray | None = None, time_s: float = 0.0,
                texture_size: int = NOISE_TEXTURE_SIZE) -> CloudField:
    """The `CloudField` of `clouds` over a planet of radius `bottom_radius_m` [m], `time_s`
    [s] after the clouds' initial state (the wind moves them), with winds given in the
    east-north-up frame whose columns (world coordinates) are `to_world` (default: the
    world axes, the north-pole observer of `render.scene.ground_viewpoint`)."""
    radius = checked_number("planet_radius_m", bottom_radius_m, 0.0, None, low_open=True)
    time = checked_number("cloud time_s", time_s, -1e12, 1e12)  # years 1-9999 from J2000
    frame = np.eye(3) if to_world is None else np.asarray(to_world, dtype=np.float64)
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    n = len(clouds.layers)
    params = np.zeros((n, N_PARAMS))
    profiles = np.zeros((n, MAX_PROFILE_NODES, 2))
    textures = np.empty((n, texture_size, texture_size, texture_size, 2), dtype=np.float32)
    extinction, albedo, asymmetry = (np.empty((n, wl.size)) for _ in range(3))
    theta = np.pi * np.linspace(0.0, 1.0, PHASE_ANGLES) ** 2
    phase = np.empty((n, PHASE_ANGLES, wl.size))
    for i, layer in enumerate(clouds.layers):
        shape = layer.shape
        wind = frame[:, 0] * layer.wind_m_s[0] + frame[:, 1] * layer.wind_m_s[1]
        speed = float(np.linalg.norm(wind))
        along = wind / speed if speed > 0.0 else frame[:, 0]
        params[i] = (radius + layer.base_altitude_m, radius + layer.top_altitude_m,
                     layer.coverage, layer.water_content_g_m3, 1.0 / shape.scale_m,
                     1.0 / shape.detail_scale_m, shape.detail_strength, shape.edge,
                     shape.coverage_variation, float(layer.kind == "sheet"),
                     len(layer.profile), *(wind * time), *along, shape.stretch - 1.0)
        profiles[i, :len(layer.profile)] = layer.profile
        textures[i] = noise_texture(shape.seed, texture_size)
        optics = layer_optics(layer, wl)
        extinction[i] = optics.mass_extinction_m2_g
        albedo[i] = optics.single_scattering_albedo
        asymmetry[i] = optics.asymmetry
        phase[i] = optics.phase.evaluate(np.cos(theta), wl)
    return CloudField(clouds, radius, wl, params, profiles, textures, extinction, albedo,
                      asymmetry, phase)


@njit(cache=True, inline="always")
def phase_table_index(nu):
    """(index, weight) of cos(scattering angle) `nu` in the phase table's angle nodes."""
    theta = np.arccos(min(1.0, max(-1.0, nu)))
    x = np.sqrt(theta / np.pi) * (PHASE_ANGLES - 1)
    i = min(int(x), PHASE_ANGLES - 2)
    return i, x - i


@njit(cache=True)
def _profile(profiles, layer, n_nodes, h):
    """Piecewise-linear profile factor at height fraction h in [0, 1]."""
    for k in range(1, n_nodes):
        h1 = profiles[layer, k, 0]
        if h <= h1:
            h0 = profiles[layer, k - 1, 0]
            t = (h - h0) / (h1 - h0)
            return profiles[layer, k - 1, 1] * (1.0 - t) + profiles[layer, k, 1] * t
    return profiles[layer, n_nodes - 1, 1]


@njit(cache=True)
def layer_water(params, profiles, textures, layer, x, y, z, r):
    """Water content w [g m^-3] of `layer` at the world point (x, y, z), |p| = r [m]
    (module docstring); 0 outside the layer's shell."""
    base, top = params[layer, BASE_R], params[layer, TOP_R]
    if r < base or r > top:
        return 0.0
    h = 0.5 if params[layer, SHEET] > 0.0 else (r - base) / (top - base)
    # moved by the wind, stretched along it
    x -= params[layer, OFFSET_X]
    y -= params[layer, OFFSET_Y]
    z -= params[layer, OFFSET_Z]
    ax, ay, az = params[layer, ALONG_X], params[layer, ALONG_Y], params[layer, ALONG_Z]
    shrink = params[layer, STRETCH_MINUS_ONE] / (1.0 + params[layer, STRETCH_MINUS_ONE])
    along = (x * ax + y * ay + z * az) * shrink
    x -= along * ax
    y -= along * ay
    z -= along * az
    n = textures.shape[1]
    tile = params[layer, INV_SCALE] * n
    coverage = params[layer, COVERAGE] * _profile(profiles, layer, int(params[layer, N_PROFILE]),
                                                  h)
    variation = params[layer, VARIATION]
    if variation > 0.0:
        large = tile / COVERAGE_TILE_RATIO
        # a different slice of the same tile: axes permuted, so no common period
        weather = sample_texture(textures, layer, 0, z * large, x * large, y * large)
        coverage *= 1.0 + variation * (2.0 * weather - 1.0)
    if coverage <= 0.0:
        return 0.0
    coverage = min(coverage, 1.0)
    shape = sample_texture(textures, layer, 0, x * tile, y * tile, z * tile)
    d = (shape - (1.0 - coverage)) / (params[layer, EDGE] * coverage)
    if d <= 0.0:
        return 0.0
    d = min(d, 1.0)
    strength = params[layer, DETAIL]
    if strength > 0.0:
        fine = params[layer, INV_DETAIL_SCALE] * n
        erosion = strength * sample_texture(textures, layer, 1, x * fine, y * fine, z * fine)
        d = (d - erosion) / (1.0 - erosion)
        if d <= 0.0:
            return 0.0
    return params[layer, WATER] * d
