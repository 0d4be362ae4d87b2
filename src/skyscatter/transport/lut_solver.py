"""Table solver: sky radiance, transmittance and ground irradiance looked up in precomputed
tables with multiple scattering (Bruneton & Neyret 2008; Bruneton 2017, functions.glsl
§Rendering).

L(x, v) = sum_s p_s(nu) S_s(r, mu, mu_s, nu) + M(r, mu, mu_s, nu)
          + [ray hits the ground at g] albedo / pi (E_sun T_sun(g) max(mu_s(g), 0) V(g)
                                                     + E_indirect(g)) T(x, g)
with S_s the single scattering of constituent s without its phase function, M the orders >= 2
and E_indirect the sky light on the ground (`transport/tables.py`). As in
`SingleScatteringSolver`, the sun disk's own radiance is not included. Observers in space are
moved to the top of the atmosphere along each ray first; rays that miss it see nothing.
Kernels: `transport/_table_lookup_kernels.py`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS, OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport import _aerial_grid_kernels, _table_lookup_kernels
from skyscatter.transport._table_common_kernels import flat_tables
from skyscatter.transport.geometry import horizontal_towards
from skyscatter.transport.table_parameterisation import COS_SUN_ZENITH_MIN, horizon_zenith_angle
from skyscatter.transport.tables import AtmosphereTables, TableResolution, precompute_tables

__all__ = ["LutSolver"]

CHUNK_RAYS = 1 << 18  # rays per kernel call, so that progress can be reported
# Samples per sunlit piece of the rays of the per-observer single-scattering table (16 k rays,
# so they can be twice those of a per-ray march)
VIEW_TABLE_SAMPLES = 64
# One observer's frames of at least SKY_GRID_MIN_RAYS rays look the tables up on a sky-view grid
# of SKY_GRID_MU view-zenith cells (the tables' mu mapping, crowded at the horizon) x
# SKY_GRID_PHI azimuths from the sun and interpolate it per pixel in the logarithm (Hillaire
# 2020, "A scalable and production ready sky and atmosphere rendering technique", Comput.
# Graph. Forum 39(4), doi:10.1111/cgf.14050, its sky-view table); the rays within
# SKY_GRID_EXACT_DEG of the sun, where the particles' phase functions peak, on a grid of their
# own around the sun, SUN_GRID_PSI angles from it (dense next to it) x SUN_GRID_CHI angles
# about it, once SUN_GRID_MIN_RAYS of them are in the frame; the rays whose grid cell may
# reach across the horizon are looked up one by one (benchmarks/bench_sky_view_grid.py,
# docs/performance.md).
SKY_GRID_MIN_RAYS = 1 << 17
SKY_GRID_MU = 256
SKY_GRID_PHI = 128
SKY_GRID_EXACT_DEG = 20.0
SUN_GRID_PSI = 128
SUN_GRID_CHI = 128
SUN_GRID_HORIZON_DEG = 2.0
# the grid's own lookups cost as much as as many rays: below 4 rays per node it saves little
SUN_GRID_MIN_RAYS = 4 * SUN_GRID_PSI * SUN_GRID_CHI
# One observer's surface points, at least AERIAL_GRID_MIN_POINTS of them, take the light the air
# scatters in front of them from a grid per frame (Hillaire 2020's aerial-perspective volume,
# `_aerial_grid_kernels`): the sky-view grid's directions on AERIAL_GRID_MU view-zenith cells x
# AERIAL_GRID_PHI azimuths, those the points fall in, x AERIAL_GRID_DEPTHS distances; the
# points within AERIAL_GRID_EXACT_DEG of the sun, and every point in twilight, are computed one
# by one (docs/performance.md, "An aerial-perspective grid per frame").
AERIAL_GRID_MIN_POINTS = 1 << 16
AERIAL_GRID_MU = 192
AERIAL_GRID_PHI = 129
AERIAL_GRID_DEPTHS = 12
AERIAL_GRID_EXACT_DEG = 20.0
# the slant optical depth where the transmittance table holds 0 (exp(-700) ~ 1e-304)
SLANT_DEPTH_MAX = 700.0


class LutSolver:
    """Answers the solver questions from precomputed tables (multiple scattering included).

    Parameters
    ----------
    profile : OpticalProfile
        The atmosphere; its wavelengths are the tables' wavelengths.
    resolution : TableResolution, optional
        Table sizes and quadrature (Bruneton 2017's sizes by default).
    orders : int
        Scattering orders (1 = single scattering only).
    min_cos_sun_zenith : float
        Smallest cos(sun zenith) tabulated (`precompute_tables`).
    tables : AtmosphereTables, optional
        Tables computed before for this profile (e.g. from a cache); skips the precomputation.
    progress : callable(done, total, stage), optional
        Passed to `precompute_tables`.
    """

    name = "lut"

    def __init__(self, profile: OpticalProfile, resolution: TableResolution | None = None,
                 orders: int = DEFAULT_SCATTERING_ORDERS, *,
                 min_cos_sun_zenith: float = COS_SUN_ZENITH_MIN,
                 tables: AtmosphereTables | None = None,
                 progress: Callable[[int, int, str], None] | None = None) -> None:
        self.profile = profile
        if tables is None:
            tables = precompute_tables(profile, resolution, orders,
                                       min_cos_sun_zenith=min_cos_sun_zenith, progress=progress)
        elif not np.array_equal(tables.wavelengths_nm, profile.wavelengths_nm):
            raise InputError("LutSolver: the tables were computed for other wavelengths "
                             f"({tables.wavelengths_nm.size} values) than the profile's "
                             f"({profile.wavelengths_nm.size})", key="tables",
                             value=tables.wavelengths_nm, allowed="the profile's wavelengths")
        self.tables = tables
        self._albedo = np.ascontiguousarray(profile.ground_albedo, dtype=np.float64)
        sun_irradiance = np.ascontiguousarray(profile.toa_irradiance, dtype=np.float64)
        scatterers = np.array(tables.scattering_constituents, dtype=np.int64)
        # the tables, and for single scattering ray-marched in twilight
        # (`_table_lookup_kernels.lit_single_scattering`) the profile
        self._lookup = _table_lookup_kernels.LookupTables(
            bottom_radius=tables.bottom_radius_m, top_radius=tables.top_radius_m,
            mu_s_min=tables.min_cos_sun_zenith, sun_angle_share=tables.sun_angle_share,
            scattering=flat_tables(tables.scattering),
            n_r=int(tables.scattering.shape[0]), n_mu=int(tables.scattering.shape[1]),
            n_mu_s=int(tables.scattering.shape[2]), n_nu=int(tables.scattering.shape[3]),
            radius_warp=tables.radius_warp, phase_table=tables.lookup_phase,
            transmittance=tables.transmittance, irradiance=tables.irradiance,
            sun_irradiance=sun_irradiance,
            sun_angular_radius=float(profile.sun_angular_radius_rad),
            h_step=float(profile.altitudes_m[1] - profile.altitudes_m[0]),
            density=np.ascontiguousarray(profile.density, dtype=np.float64),
            scatterers=scatterers,
            single_factor=np.ascontiguousarray(  # E_sun beta_s, (n_s, n_wl)
                sun_irradiance[None, :] * profile.scattering_per_density[scatterers].reshape(
                    scatterers.size, profile.n_wavelengths), dtype=np.float64),
            slant_depth=_depth(tables.transmittance, SLANT_DEPTH_MAX),
            peak_depth=_depth(tables.peak_transmittance, float(tables.aureole_limits[0])),
            aureole_shape=tables.aureole_shape,
            aureole_blur=tables.aureole_blur,
            aureole_x_max=float(tables.aureole_limits[0]),
            aureole_psi_max=float(tables.aureole_limits[1]))

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1] seen from `position` (planet-centred
        [m], (3,) or broadcastable to the directions) along `view_directions` (..., 3; any
        length), with the sun along `sun_direction` (3,). Returns (..., n_wl). `progress(n)` is
        called with the number of rays done after each chunk.

        Single scattering is looked up in the table while the sun at the ray's start is more
        than 5 deg above the horizon and ray-marched through the sunlit parts of the ray
        (with the transmittance table) once it is below the horizon, blended in between
        (`_table_lookup_kernels.exact_single_weight`): the table's interpolation in the sun's zenith
        cosine leaks light into the planet's shadow in twilight (docs/physics/tables.md)."""
        origins, directions, shape = _rays(position, view_directions)
        sun = _sun(sun_direction)
        result = np.empty((directions.shape[0], self.profile.n_wavelengths))
        view_table = self._view_table(origins, sun)
        aureole_table = self._aureole_table(origins, sun, directions.shape[0])
        if self._uses_sky_view_grid(origins, directions.shape[0]):
            self._sky_from_view_grid(origins[0], directions, sun, view_table, aureole_table,
                                     result, progress)
        else:
            self._sky_per_ray(origins, directions, sun, view_table, aureole_table, result,
                              progress)
        return result.reshape(shape + (self.profile.n_wavelengths,))

    def _sky_per_ray(self, origins: np.ndarray, directions: np.ndarray, sun: np.ndarray,
                     view_table: np.ndarray, aureole_table: np.ndarray, out: np.ndarray,
                     progress: Callable[[int], None] | None) -> None:
        """`sky_radiance` looked up for every ray, in chunks, into out (n_ray, n_wl)."""
        for start in range(0, directions.shape[0], CHUNK_RAYS):
            stop = min(start + CHUNK_RAYS, directions.shape[0])
            _table_lookup_kernels.sky_radiance_rays(
                origins if origins.shape[0] == 1 else origins[start:stop],
                directions[start:stop], sun, self._lookup, self._albedo, view_table,
                aureole_table, out[start:stop])
            if progress is not None:
                progress(stop - start)

    def _uses_sky_view_grid(self, origins: np.ndarray, n_rays: int) -> bool:
        """Whether `sky_radiance` interpolates a sky-view grid (module constants): one
        observer inside the atmosphere and at least SKY_GRID_MIN_RAYS rays."""
        return n_rays >= SKY_GRID_MIN_RAYS and self._one_observer_inside(origins)

    def _one_observer_inside(self, origins: np.ndarray) -> bool:
        """Whether `origins` is one observer (1, 3) inside the atmosphere (ground included)."""
        if origins.shape[0] != 1:
            return False
        r = float(np.linalg.norm(origins[0]))
        return self.tables.bottom_radius_m <= r <= self.tables.top_radius_m

    def _sky_from_view_grid(self, origin: np.ndarray, directions: np.ndarray, sun: np.ndarray,
                            view_table: np.ndarray, aureole_table: np.ndarray, out: np.ndarray,
                            progress: Callable[[int], None] | None) -> None:
        """`sky_radiance` of one observer from a sky-view grid (module constants): the rays
        within SKY_GRID_EXACT_DEG of the sun looked up one by one, the others interpolated."""
        t = self.tables
        r = float(np.linalg.norm(origin))
        up = origin / r
        nodes = _table_lookup_kernels.sky_view_grid_nodes(
            r, SKY_GRID_MU, SKY_GRID_PHI, t.bottom_radius_m, t.top_radius_m)
        log_grid = self._log_radiance_grid(origin, nodes @ _sun_frame(up, sun), sun,
                                           view_table, aureole_table)
        exact = np.empty(directions.shape[0], dtype=np.bool_)
        _table_lookup_kernels.sky_view_grid_lookup(
            log_grid, up, sun, float(np.cos(np.radians(SKY_GRID_EXACT_DEG))), t.bottom_radius_m,
            r, directions, out, exact)
        near_sun = np.flatnonzero(exact)
        if near_sun.size:
            values = np.empty((near_sun.size, self.profile.n_wavelengths))
            self._sky_near_sun(origin, r, np.ascontiguousarray(directions[near_sun]), sun,
                               view_table, aureole_table, values)
            out[near_sun] = values
        if progress is not None:
            progress(directions.shape[0])

    def _log_radiance_grid(self, origin: np.ndarray, nodes: np.ndarray, sun: np.ndarray,
                           view_table: np.ndarray, aureole_table: np.ndarray) -> np.ndarray:
        """The logarithm of `sky_radiance` of one observer along the grid's view directions
        `nodes` (n_a, n_b, 3), floored at VIEW_TABLE_FLOOR: (n_a, n_b, n_wl)."""
        grid = np.empty((nodes.shape[0] * nodes.shape[1], self.profile.n_wavelengths))
        self._sky_per_ray(origin[None], np.ascontiguousarray(nodes.reshape(-1, 3)), sun,
                          view_table, aureole_table, grid, None)
        return np.log(np.maximum(grid, _table_lookup_kernels.VIEW_TABLE_FLOOR)).reshape(
            nodes.shape[0], nodes.shape[1], -1)

    def _sky_near_sun(self, origin: np.ndarray, r: float, directions: np.ndarray,
                      sun: np.ndarray, view_table: np.ndarray, aureole_table: np.ndarray,
                      out: np.ndarray) -> None:
        """`sky_radiance` of one observer at `origin`, radius r [m], along `directions` within
        SKY_GRID_EXACT_DEG of the sun, into out: from a sun grid (module constants) when there
        are at least SUN_GRID_MIN_RAYS, each ray whose cell may reach across the horizon (or
        comes within SUN_GRID_HORIZON_DEG of it) looked up alone."""
        if directions.shape[0] < SUN_GRID_MIN_RAYS:
            self._sky_per_ray(origin[None], directions, sun, view_table, aureole_table, out,
                              None)
            return
        up = origin / r
        psi_max = float(np.radians(SKY_GRID_EXACT_DEG))
        log_grid = self._log_radiance_grid(
            origin, _table_lookup_kernels.sun_grid_nodes(up, sun, SUN_GRID_PSI, SUN_GRID_CHI,
                                                         psi_max),
            sun, view_table, aureole_table)
        exact = np.empty(directions.shape[0], dtype=np.bool_)
        _table_lookup_kernels.sun_grid_lookup(
            log_grid, up, sun, psi_max, horizon_zenith_angle(r, self.tables.bottom_radius_m),
            float(np.radians(SUN_GRID_HORIZON_DEG)), directions, out, exact)
        at_horizon = np.flatnonzero(exact)
        if at_horizon.size:
            values = np.empty((at_horizon.size, self.profile.n_wavelengths))
            self._sky_per_ray(origin[None], np.ascontiguousarray(directions[at_horizon]), sun,
                              view_table, aureole_table, values, None)
            out[at_horizon] = values

    def _view_table(self, origins: np.ndarray, sun: np.ndarray) -> np.ndarray:
        """Single scattering of every view direction of the one observer in `origins` (1, 3)
        when it is inside the atmosphere and the sun is low enough for the lookups to use it
        (`_table_lookup_kernels.single_scattering_view_table`); otherwise an empty table, and the
        kernel marches each ray itself."""
        t = self.tables
        n_s = len(t.scattering_constituents)
        empty = np.zeros((0, 2, n_s, self.profile.n_wavelengths))
        if origins.shape[0] != 1:
            return empty
        r = float(np.linalg.norm(origins[0]))
        mu_s = float(origins[0] @ sun) / r if r > 0.0 else 1.0
        if r > t.top_radius_m or _table_lookup_kernels.exact_single_weight(mu_s) <= 0.0:
            return empty
        return _table_lookup_kernels.single_scattering_view_table(
            max(r, t.bottom_radius_m), mu_s, VIEW_TABLE_SAMPLES, self._lookup)

    def _aureole_table(self, origins: np.ndarray, sun: np.ndarray, n_rays: int) -> np.ndarray:
        """The Poisson law of the aureole's peak events for every view near the sun of the one
        observer in `origins` (1, 3) inside the atmosphere
        (`_table_lookup_kernels.aureole_view_table`), when the tables have an aureole and the
        call has at least as many rays as the table has nodes (fewer rays compute it faster
        one by one); otherwise an empty table, and the kernel computes it per ray."""
        lookup = self._lookup
        nodes = _table_lookup_kernels.AUREOLE_VIEW_PSI * _table_lookup_kernels.AUREOLE_VIEW_CHI
        if (n_rays < nodes or not lookup.aureole_psi_max > 0.0
                or not self._one_observer_inside(origins)):
            return np.zeros((0, 0, 2, self.profile.n_wavelengths))
        r = float(np.linalg.norm(origins[0]))
        return _table_lookup_kernels.aureole_view_table(r, float(origins[0] @ sun) / r, lookup)

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] from `position` along `directions` over `distance_m` [m] (inf:
        out of the atmosphere, towards a light source; 0 when the ground blocks the path, so
        for a light below the horizon), from the transmittance table (ratio of two lookups,
        Bruneton 2017 `GetTransmittance`). Returns (..., n_wl)."""
        origins, dirs, shape = _rays(position, directions)
        distances = _writable(np.broadcast_to(np.asarray(distance_m, dtype=np.float64),
                                              shape).reshape(-1))
        t = self.tables
        result = _table_lookup_kernels.transmittance_rays(
            origins, dirs, distances, t.bottom_radius_m, t.top_radius_m, t.transmittance)
        return result.reshape(shape + (self.profile.n_wavelengths,))

    def aerial_perspective(self, position: ArrayLike, points: ArrayLike,
                           sun_direction: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(inscattered, transmittance) between the observer at `position` (planet-centred
        [m], (3,) or broadcastable) and `points` (..., 3) [m] in the atmosphere or on the
        ground: the radiance the air between them scatters towards the observer
        [W m^-2 sr^-1 nm^-1] and the fraction of the points' own radiance that reaches it [-],
        each (..., n_wl). An object at p with radiance L_p is seen as T L_p + inscattered.

        Single scattering is the difference of two table lookups (Bruneton 2017) by day and,
        as in `sky_radiance`, ray-marched through the sunlit part of the segment once the sun
        at either of its ends nears the horizon (`_table_lookup_kernels.exact_single_weight`), with
        the orders >= 2 interpolated geometrically in the sun's zenith cosine. The sun's aureole
        of light scattered twice or more in forward peaks (`transport.aureole`) is the sky's
        alone: objects in front of the sun are not veiled by it."""
        origins, targets, shape = _rays(position, points)
        sun = _sun(sun_direction)
        p = self.profile
        inscattered = np.empty((targets.shape[0], p.n_wavelengths))
        transmittance = np.empty_like(inscattered)
        _table_lookup_kernels.aerial_perspective_points(
            origins, targets, sun, self._lookup, inscattered, transmittance)
        return (inscattered.reshape(shape + (p.n_wavelengths,)),
                transmittance.reshape(shape + (p.n_wavelengths,)))

    def surface_radiance(self, position: ArrayLike, points: ArrayLike, normals: ArrayLike,
                         albedo: ArrayLike, sun_direction: ArrayLike, *,
                         lit: ArrayLike | None = None) -> np.ndarray:
        """Radiance [W m^-2 sr^-1 nm^-1] (n, n_wl) that reaches the observer at `position` (3,)
        from Lambertian surfaces at `points` (n, 3) facing unit `normals` (n, 3), with spectral
        `albedo` ((n, n_wl) or (n_wl,)), receiving the part `lit` (n,) in [0, 1] of the
        sunlight (True/False for in or out of a terrain shadow, a cloud's transmittance;
        default 1): aerial perspective plus the reflected sun and sky light seen through it,
        L_in + T albedo / pi (lit E_sun + E_sky) (`aerial_perspective`, `ground_irradiance`;
        one pass over the points)."""
        p = self.profile
        targets = _writable(np.asarray(points, dtype=np.float64).reshape(-1, 3))
        n = targets.shape[0]
        facing = _writable(np.broadcast_to(np.asarray(normals, dtype=np.float64), (n, 3)))
        reflectance = _writable(np.asarray(albedo, dtype=np.float64).reshape(
            -1, p.n_wavelengths))
        sunlit = (np.ones(n) if lit is None
                  else np.ascontiguousarray(np.broadcast_to(lit, (n,)), dtype=np.float64))
        out = np.empty((n, p.n_wavelengths))
        origin = _writable(np.asarray(position, dtype=np.float64).reshape(3))
        sun = _sun(sun_direction)
        if self._uses_aerial_grid(origin, sun, n):
            self._surface_radiance_from_grid(origin, targets, facing, sunlit, reflectance, sun,
                                             out)
        else:
            self._surface_radiance_per_point(origin, targets, facing, sunlit, reflectance, sun,
                                             out)
        return out

    def _surface_radiance_per_point(self, origin: np.ndarray, points: np.ndarray,
                                    normals: np.ndarray, lit: np.ndarray, albedo: np.ndarray,
                                    sun: np.ndarray, out: np.ndarray) -> None:
        """`surface_radiance` with the aerial perspective of every point computed alone (all
        `exact`: the kernel reads no grid)."""
        no_grid = np.zeros((0, 0, 0, self.profile.n_wavelengths))
        _aerial_grid_kernels.surface_radiance_points(
            origin, points, normals, lit, albedo, sun, self._lookup, no_grid, 0, 0, 0, 0, 0.0,
            np.ones(points.shape[0], dtype=np.bool_), out)

    def _uses_aerial_grid(self, origin: np.ndarray, sun: np.ndarray, n_points: int) -> bool:
        """Whether `surface_radiance` takes the aerial perspective from a grid (module
        constants): at least AERIAL_GRID_MIN_POINTS points of one observer inside the
        atmosphere, by day. In twilight (the lookups march single scattering,
        `exact_single_weight`) the Earth's shadow crosses the views by the horizon within a
        fraction of the grid's cells: up to 15 % off seen from 3 km with the sun 2 deg below
        the horizon, so the points are computed one by one."""
        if n_points < AERIAL_GRID_MIN_POINTS or not self._one_observer_inside(origin[None]):
            return False
        mu_s = float(origin @ sun) / float(np.linalg.norm(origin))
        return _table_lookup_kernels.exact_single_weight(mu_s) <= 0.0

    def _surface_radiance_from_grid(self, origin: np.ndarray, points: np.ndarray,
                                    normals: np.ndarray, lit: np.ndarray, albedo: np.ndarray,
                                    sun: np.ndarray, out: np.ndarray) -> None:
        """`surface_radiance` of one observer inside the atmosphere with the light the air
        scatters in front of the points from an aerial-perspective grid (module constants):
        the cells of the sky-view grid the points fall in, at AERIAL_GRID_DEPTHS distances,
        L_in / (1 - T) from `aerial_perspective_points` at its nodes."""
        t = self.tables
        n = points.shape[0]
        i_mu, k_phi = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
        distance, exact = np.empty(n), np.empty(n, dtype=np.bool_)
        _aerial_grid_kernels.aerial_grid_cells(
            origin, points, sun, float(np.cos(np.radians(AERIAL_GRID_EXACT_DEG))),
            t.bottom_radius_m, t.top_radius_m, AERIAL_GRID_MU, AERIAL_GRID_PHI, i_mu, k_phi,
            distance, exact)
        served = ~exact
        if not served.any():
            self._surface_radiance_per_point(origin, points, normals, lit, albedo, sun, out)
            return
        i_first, i_last = int(i_mu[served].min()), int(i_mu[served].max()) + 1
        k_first, k_last = int(k_phi[served].min()), int(k_phi[served].max()) + 1
        d_max = float(distance[served].max())
        r = float(np.linalg.norm(origin))
        directions = _table_lookup_kernels.sky_view_grid_nodes(
            r, AERIAL_GRID_MU, AERIAL_GRID_PHI, t.bottom_radius_m, t.top_radius_m)[
                i_first:i_last + 1, k_first:k_last + 1] @ _sun_frame(origin / r, sun)
        nodes = _aerial_grid_kernels.aerial_grid_node_points(
            origin, np.ascontiguousarray(directions), d_max, t.bottom_radius_m,
            t.top_radius_m, AERIAL_GRID_DEPTHS)
        n_wl = self.profile.n_wavelengths
        inscatter = np.empty((nodes.size // 3, n_wl))
        transmittance = np.empty_like(inscatter)
        _table_lookup_kernels.aerial_perspective_points(
            origin[None], nodes.reshape(-1, 3), sun, self._lookup, inscatter, transmittance)
        extinguished = 1.0 - transmittance
        ratio = np.divide(inscatter, extinguished, out=np.zeros_like(inscatter),
                          where=extinguished > 0.0).reshape(nodes.shape[:3] + (n_wl,))
        ratio[:, :, 0] = ratio[:, :, 1]  # at the observer 0 / 0: the next node's
        _aerial_grid_kernels.surface_radiance_points(
            origin, points, normals, lit, albedo, sun, self._lookup, ratio, AERIAL_GRID_MU,
            AERIAL_GRID_PHI, i_first, k_first, d_max, exact, out)

    def ground_irradiance(self, position: ArrayLike, sun_direction: ArrayLike,
                          normals: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(direct, diffuse) spectral irradiance [W m^-2 nm^-1] on surfaces at `position`
        (planet-centred [m], (..., 3)), each (..., n_wl); horizontal unless unit `normals`
        (broadcastable to the positions) are given. Direct: E_sun T_sun V max(n . s, 0) with
        V the visible part of the disk; diffuse: the indirect-irradiance table (sky light of
        orders 1 .. orders-1; none for orders = 1) times the part of the sky the surface sees,
        (1 + n . up) / 2."""
        positions = np.asarray(position, dtype=np.float64)
        shape = positions.shape[:-1]
        flat = _writable(positions.reshape(-1, 3))
        if normals is None:
            facing = flat / np.linalg.norm(flat, axis=1, keepdims=True)
        else:
            facing = _writable(np.broadcast_to(np.asarray(normals, dtype=np.float64),
                                               positions.shape).reshape(-1, 3))
        sun = _sun(sun_direction)
        p = self.profile
        direct, diffuse = _table_lookup_kernels.ground_irradiance_points(flat, facing, sun,
                                                                         self._lookup)
        n_wl = p.n_wavelengths
        return direct.reshape(shape + (n_wl,)), diffuse.reshape(shape + (n_wl,))


def _depth(transmittance: np.ndarray, where_zero: float) -> np.ndarray:
    """-ln of a transmittance table (n_r_t, n_mu_t, n_wl), `where_zero` where it is 0."""
    with np.errstate(divide="ignore"):
        return np.where(transmittance > 0.0, -np.log(transmittance), where_zero)


def _writable(array: np.ndarray) -> np.ndarray:
    """`array` as a writable C-ordered float64 array, copied only when needed: the kernels
    then meet one array type and compile once."""
    array = np.ascontiguousarray(array, dtype=np.float64)
    return array if array.flags.writeable else array.copy()


def _sun_frame(up: np.ndarray, sun: np.ndarray) -> np.ndarray:
    """Rows: the local x (towards the sun's azimuth), y and z (up) axes of an observer whose
    vertical is the unit `up`; `local @ frame` turns local directions into world ones."""
    x_axis = horizontal_towards(up, sun)
    return np.stack([x_axis, np.cross(up, x_axis), up])


def _sun(sun_direction: ArrayLike) -> np.ndarray:
    """Unit sun direction (3,)."""
    sun = np.array(sun_direction, dtype=np.float64).reshape(3)
    return sun / np.linalg.norm(sun)


def _rays(position: ArrayLike, directions: ArrayLike
          ) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """(origins (1, 3) or (n, 3), directions (n, 3), broadcast shape S) for the kernels, which
    normalise the directions; the inputs are used in place where they are already writable
    float64 C-ordered arrays of the full shape."""
    dirs = np.asarray(directions, dtype=np.float64)
    origin = np.asarray(position, dtype=np.float64)
    shape = np.broadcast_shapes(dirs.shape, origin.shape)[:-1]
    if dirs.shape != shape + (3,):
        dirs = np.broadcast_to(dirs, shape + (3,))
    flat_dirs = _writable(dirs).reshape(-1, 3)
    if origin.ndim == 1:
        return _writable(origin.reshape(1, 3)), flat_dirs, shape
    return _writable(np.broadcast_to(origin, shape + (3,))).reshape(-1, 3), flat_dirs, shape
