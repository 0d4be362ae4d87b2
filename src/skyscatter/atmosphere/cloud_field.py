"""The water content of cloud layers at any point of a planet, for the kernels that march it.

`cloud_field` turns `Clouds` (`atmosphere.cloud_config`) into arrays: per layer its shell, the
parameters of its shape, its noise tile (`atmosphere.cloud_noise`), and its optics per gram of
water on the render's wavelengths (`optics.cloud_optics`). `layer_water` (a kernel of
`atmosphere._cloud_sampling`, re-exported here) is the one definition of the water content
w(p) [g m^-3] that the renderer and the Monte Carlo reference both read:

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

from skyscatter.atmosphere._cloud_sampling import (
    ALONG_X,
    BASE_R,
    DETAIL,
    N_PARAMS,
    PHASE_ANGLES,
    SHEET,
    TOP_R,
    WATER,
    layer_water,
    phase_table_index,
)
from skyscatter.atmosphere.cloud_config import MAX_PROFILE_NODES, CloudLayer, Clouds
from skyscatter.atmosphere.cloud_noise import NOISE_TEXTURE_SIZE, noise_texture
from skyscatter.checks import checked_number
from skyscatter.optics.cloud_optics import CloudOptics, ice_cloud_optics, liquid_cloud_optics

__all__ = [  # the sampling kernels and the columns of `CloudField.params` re-exported
    "ALONG_X",
    "BASE_R",
    "DETAIL",
    "N_PARAMS",
    "PHASE_ANGLES",
    "SHEET",
    "TOP_R",
    "WATER",
    "CloudField",
    "cloud_field",
    "layer_optics",
    "layer_water",
    "phase_table_index",
]



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
