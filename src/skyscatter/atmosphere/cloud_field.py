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

Whole-planet clouds. A layer's coverage map M (`atmosphere.cloud_maps`) multiplies c by
M(latitude, longitude) of p, in planet-fixed coordinates: p rotated from the world frame
by E(lat_0, lon_0) to_world^T, E the east-north-up axes of the observer at (lat_0, lon_0)
in planet-fixed coordinates (the identity for an orbit camera, whose world frame is
planet-fixed). The map stays fixed to the planet; the wind moves the noise under it.

Grid layers (`type = "grid"`, `atmosphere.cloud_grids`) replace the noise by water read
trilinearly from a grid in a box that stands on the layer's base, centred on the observer
(the origin of the east-north-up frame `to_world`), moved by the wind as the noise is
(`_cloud_sampling` module docstring has the equations). They have no far field (their
`FAR_START` is `NEVER_FAR`: the march reads the grid at any distance), no column statistics
and a zero `COVERAGE` column (so a reader of the noise alone, such as the viewer, draws
nothing for them rather than made-up noise); their `WATER` column is the grid's largest value
(the Monte Carlo's majorant).

Far away a layer's tile is far below a pixel: a march would sample one random point of it
per pixel. Beyond the view-ray distance `FAR_START` = 0.5 scale / alpha (alpha the angle of
a pixel: where the pixel's footprint is half a tile) the renderer blends, up to `FAR_END` =
1.5 scale / alpha, to the independent column approximation (Cahalan et al. 1994, J. Atmos. Sci.
51, 2434, doi:10.1175/1520-0469(1994)051<2434:TAOFSC>2.0.CO;2): the pixel sees a fraction
c_col of cloudy columns and 1 - c_col clear (`transport._cloud_kernels`); the cloudy ones
in 5 shares (2, 4, 8, 16 and 70 % of them, thinnest first), each a uniform slab holding the
mean water path of its share (reflectance and transmittance are not linear in the optical
depth: one mean path would make the columns too opaque, the thin edges most of all). c_col
and the paths are measured on this field (`_cloud_sampling.column_statistics`: 4096 vertical
columns across 7.3 tiles, so the coverage variation is in the statistics) for map factors 0,
1/16, ..., 1, and read at the map's value where the view ray crosses the layer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.atmosphere._cloud_sampling import (
    ALONG_X,
    BASE_R,
    COLUMN_NODES,
    COLUMN_VALUES,
    COVERAGE,
    COVERAGE_TILE_RATIO,
    DETAIL,
    FAR_END,
    FAR_START,
    GRID_AXES,
    GRID_DX,
    GRID_NX,
    GRID_PERIODIC,
    INV_SCALE,
    MAP_HEIGHT,
    MAP_WIDTH,
    N_PARAMS,
    OFFSET_X,
    PHASE_ANGLES,
    PLANET,
    SHEET,
    TOP_R,
    VARIATION,
    WATER,
    column_statistics,
    layer_water,
    phase_table_index,
)
from skyscatter.atmosphere.cloud_config import MAX_PROFILE_NODES, CloudLayer, Clouds
from skyscatter.atmosphere.cloud_noise import NOISE_TEXTURE_SIZE, noise_texture
from skyscatter.checks import LATITUDE_DEG, checked_number
from skyscatter.optics.cloud_optics import CloudOptics, ice_cloud_optics, liquid_cloud_optics

__all__ = [  # the sampling kernels and the columns of `CloudField.params` re-exported
    "ALONG_X",
    "BASE_R",
    "DETAIL",
    "GRID_NX",
    "NEVER_FAR",
    "N_PARAMS",
    "PHASE_ANGLES",
    "SHEET",
    "TOP_R",
    "WATER",
    "CloudField",
    "cloud_field",
    "column_table",
    "layer_optics",
    "layer_water",
    "phase_table_index",
]



@dataclass(frozen=True, eq=False)
class CloudField:
    """Arrays of cloud layers for the kernels (module docstring); layers lowest first.

    params (n_layers, N_PARAMS); profiles (n_layers, MAX_PROFILE_NODES + n_data, 2): the
    profile nodes, then each layer's column statistics and coverage map
    (`_cloud_sampling` module docstring); textures
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
                texture_size: int = NOISE_TEXTURE_SIZE, latitude_deg: float = 0.0,
                longitude_deg: float = 0.0, pixel_angle_rad: float | None = None
                ) -> CloudField:
    """The `CloudField` of `clouds` over a planet of radius `bottom_radius_m` [m], `time_s`
    [s] after the clouds' initial state (the wind moves them), with winds given in the
    east-north-up frame whose columns (world coordinates) are `to_world` (default: the
    world axes, the north-pole observer of `render.scene.ground_viewpoint`) of an observer
    at `latitude_deg`, `longitude_deg` [deg] (they orient coverage maps; module docstring).
    `pixel_angle_rad` [rad], the angle of a pixel, sets where the far field starts (default
    0.006, the footprint the march's steps assume: `transport._cloud_kernels.STEP_GROWTH`)."""
    radius = checked_number("planet_radius_m", bottom_radius_m, 0.0, None, low_open=True)
    time = checked_number("cloud time_s", time_s, -1e12, 1e12)  # years 1-9999 from J2000
    pixel = checked_number("pixel_angle_rad", 0.006 if pixel_angle_rad is None
                           else pixel_angle_rad, 0.0, np.pi, low_open=True)
    frame = np.eye(3) if to_world is None else np.asarray(to_world, dtype=np.float64)
    planet = _observer_axes(LATITUDE_DEG.check("latitude_deg", latitude_deg),
                            checked_number("longitude_deg", longitude_deg, -1e6, 1e6)) @ frame.T
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    n = len(clouds.layers)
    params = np.zeros((n, N_PARAMS))
    data_values = max([layer.coverage_map.values.size for layer in clouds.layers
                       if layer.coverage_map is not None]
                      + [layer.grid.water_g_m3.size for layer in clouds.layers
                         if layer.grid is not None], default=0)
    column_rows = COLUMN_NODES * COLUMN_VALUES // 2
    profiles = np.zeros((n, MAX_PROFILE_NODES + column_rows + (data_values + 1) // 2, 2))
    textures = np.empty((n, texture_size, texture_size, texture_size, 2), dtype=np.float32)
    extinction, albedo, asymmetry = (np.empty((n, wl.size)) for _ in range(3))
    theta = np.pi * np.linspace(0.0, 1.0, PHASE_ANGLES) ** 2
    phase = np.empty((n, PHASE_ANGLES, wl.size))
    for i, layer in enumerate(clouds.layers):
        shape = layer.shape
        wind = frame[:, 0] * layer.wind_m_s[0] + frame[:, 1] * layer.wind_m_s[1]
        speed = float(np.linalg.norm(wind))
        along = wind / speed if speed > 0.0 else frame[:, 0]
        params[i, :PLANET] = (radius + layer.base_altitude_m, radius + layer.top_altitude_m,
                     layer.coverage, layer.water_content_g_m3, 1.0 / shape.scale_m,
                     1.0 / shape.detail_scale_m, shape.detail_strength, shape.edge,
                     shape.coverage_variation, float(layer.kind == "sheet"),
                     len(layer.profile), *(wind * time), *along, shape.stretch - 1.0)
        profiles[i, :len(layer.profile)] = layer.profile
        params[i, PLANET:PLANET + 9] = planet.ravel()
        if layer.coverage_map is not None:
            values = layer.coverage_map.values
            params[i, MAP_HEIGHT], params[i, MAP_WIDTH] = values.shape
            flat = profiles[i, MAX_PROFILE_NODES + column_rows:].reshape(-1)
            flat[:values.size] = values.ravel()
        params[i, GRID_AXES:GRID_AXES + 9] = frame.T.ravel()
        if layer.grid is not None:
            _grid_columns(params[i], profiles[i, MAX_PROFILE_NODES + column_rows:], layer)
            textures[i] = 0.0
        else:
            params[i, FAR_START] = FAR_FOOTPRINTS[0] * shape.scale_m / pixel
            params[i, FAR_END] = FAR_FOOTPRINTS[1] * shape.scale_m / pixel
            textures[i] = noise_texture(shape.seed, texture_size)
        if layer.grid is None:
            profiles[i, MAX_PROFILE_NODES:MAX_PROFILE_NODES + column_rows] = column_table(
                params[i], profiles[i], textures[i]).reshape(column_rows, 2)
        optics = layer_optics(layer, wl)
        extinction[i] = optics.mass_extinction_m2_g
        albedo[i] = optics.single_scattering_albedo
        asymmetry[i] = optics.asymmetry
        phase[i] = optics.phase.evaluate(np.cos(theta), wl)
    return CloudField(clouds, radius, wl, params, profiles, textures, extinction, albedo,
                      asymmetry, phase)


NEVER_FAR = 1e30  # [m] FAR_START and FAR_END of a layer without a far field (grid layers)


def _grid_columns(row: np.ndarray, data: np.ndarray, layer: CloudLayer) -> None:
    """Fill a grid layer's row of `CloudField.params` (its coverage, far field and grid
    columns; module docstring) and its data rows of `CloudField.profiles` (the grid)."""
    grid = layer.grid
    row[COVERAGE] = 0.0
    row[FAR_START] = row[FAR_END] = NEVER_FAR
    row[GRID_NX:GRID_NX + 3] = grid.water_g_m3.shape
    row[GRID_DX:GRID_DX + 3] = grid.spacing_m
    row[GRID_PERIODIC] = float(grid.periodic)
    data.reshape(-1)[:grid.water_g_m3.size] = grid.water_g_m3.ravel()


# The far field blends in from where a pixel spans half a tile to where it spans 1.5: a march
# that samples one point per pixel aliases a pattern of less than two pixels per tile.
FAR_FOOTPRINTS = (0.5, 1.5)
COLUMNS = 4096  # columns of `column_table`: c_col to ~0.8 % (binomial, c = 0.5)
COLUMN_LEVELS = 48  # heights per column: 33 m steps in a 1.6 km cumulus layer


def column_table(params: np.ndarray, profile: np.ndarray, texture: np.ndarray) -> np.ndarray:
    """(COLUMN_NODES, COLUMN_VALUES) cloudy column fraction [-] and the mean water paths
    [g m^-2] of the `COLUMN_SHARES` of cloudy columns of one layer (its row of
    `CloudField.params`, its profile rows and noise tile) at map factors i / (COLUMN_NODES - 1)
    (module docstring; `_cloud_sampling.column_statistics`): the wind's offset, the stretch's
    axis and the map left out."""
    row = np.array(params, dtype=np.float64)[None].copy()
    row[0, OFFSET_X:OFFSET_X + 3] = 0.0
    row[0, ALONG_X:ALONG_X + 3] = (1.0, 0.0, 0.0)
    row[0, MAP_WIDTH] = 0.0
    stretch = 1.0 + max(row[0, ALONG_X + 3], 0.0)
    side = (COVERAGE_TILE_RATIO if row[0, VARIATION] > 0.0 else 2.0) * stretch / row[0, INV_SCALE]
    levels = 1 if row[0, SHEET] > 0.0 else COLUMN_LEVELS
    out = np.zeros((COLUMN_NODES, COLUMN_VALUES))
    column_statistics(row, np.ascontiguousarray(profile[None]), np.ascontiguousarray(
        texture[None]), 0, side, COLUMNS, levels, out)
    return out


def _observer_axes(latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """(3, 3) east, north, up (columns) of the point at (latitude, longitude) [deg] in
    planet-fixed coordinates (z to the north pole, x to longitude 0), as
    `render.scene.orbit_viewpoint`."""
    lat, lon = np.radians(latitude_deg), np.radians(longitude_deg)
    up = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    return np.column_stack([east, np.cross(up, east), up])
