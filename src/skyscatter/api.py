"""The public Python API: load an atmosphere, render sky images, compute sky radiance.

    from skyscatter import api
    atmosphere = api.load_atmosphere("earth")
    image = api.render(atmosphere, api.FisheyeCamera(512), sun_zenith_deg=60.0)
    api.save_image(image, png_path="sky.png", exr_path="sky.exr")

The whole sky at a date and place (sun, moon, stars; Earth and Mars presets):

    berlin = api.make_observer("2024-06-21T21:30+02:00", 52.52, 13.40)
    image = api.render_at(atmosphere, api.FisheyeCamera(512), berlin)
    api.save_image(image, png_path="berlin.png",
                   options=api.ImageOptions(adapt_to_night=True, operator="reinhard"))
    api.timelapse(atmosphere, api.FisheyeCamera(256), times, 52.52, 13.40,
                  video_path="night.mp4", frames_dir="night_frames",
                  image=api.ImageOptions(operator="reinhard"))

Which atmosphere made a measured sky, with uncertainties (docs/fit.md):

    result = api.fit("earth", "almucantar.csv",
                     ["constituent[2].optics.optical_depth=0.01:1"], refine="lut")
    result.estimates, result.uncertainties, result.report

Past the leading arguments (at most five) every option is keyword-only: name it.

Every function checks its arguments before any work and raises `skyscatter.InputError` (the
message the command line prints) for a value that is not finite, out of its range, of the
wrong type, or that would cost more memory than this computer has or more than an hour of
computing (`render.budget`; `allow_large=True` lifts that limit).
"""

from __future__ import annotations

import contextlib
import datetime
import ipaddress
import itertools
import json
import math
import re
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from skyscatter.astro.mars_time import utc_from_mars_sol_date
from skyscatter.astro.time import check_utc, parse_time
from skyscatter.atmosphere.cloud_config import Clouds, list_cloud_presets, load_clouds
from skyscatter.atmosphere.cloud_field import CloudField, cloud_field
from skyscatter.atmosphere.config import list_presets, load_atmosphere
from skyscatter.atmosphere.config_overrides import load_document, parse_values
from skyscatter.atmosphere.gas import describe_gas
from skyscatter.atmosphere.model import MAX_SCATTERING_ORDERS, Atmosphere
from skyscatter.atmosphere.variants import load_variant, with_ground_albedo
from skyscatter.checks import (
    ALTITUDE_M,
    ANGLE_DEG,
    LATITUDE_DEG,
    ZENITH_DEG,
    Bounds,
    checked_array,
    checked_instance,
    checked_integer,
    checked_number,
)
from skyscatter.dask_cluster import dask_client, import_distributed, map_in_order
from skyscatter.datasets import grid_dataset, import_xarray, rows_dataset, write_netcdf, write_zarr
from skyscatter.errors import InputError
from skyscatter.fit.forward import FAST_SOLVERS, SolverModel
from skyscatter.fit.image_samples import image_rows
from skyscatter.fit.measurements import measurements_from_rows, read_measurements, read_rows
from skyscatter.fit.parameters import FreeParameter, checked_free
from skyscatter.fit.retrieval import Retrieval, retrieve
from skyscatter.fit.sweep_model import SweepModel
from skyscatter.output_files import check_writable_file, check_writable_folder, staged_outputs
from skyscatter.output_metadata import output_metadata
from skyscatter.render.albedo_map import AlbedoMap
from skyscatter.render.budget import (
    BYTES_PER_ROW,
    MAX_FRAMES,
    MAX_SAMPLES,
    check_cost,
    image_memory_bytes,
)
from skyscatter.render.camera import (
    MAX_SIDE_PIXELS,
    Camera,
    EquirectangularCamera,
    FisheyeCamera,
    PerspectiveCamera,
)
from skyscatter.render.cube_map import CUBE_LAYOUTS, CubeMapCamera
from skyscatter.render.environment_light import environment_light as sky_light
from skyscatter.render.exposure import display_rgb8, metered_ev100
from skyscatter.render.image_io import display_format, display_image_writer, exr_writer
from skyscatter.render.image_options import EXR_CONTENTS, EXR_UNITS, ImageOptions
from skyscatter.render.octahedral import OctahedralCamera
from skyscatter.render.paraboloid import ParaboloidCamera
from skyscatter.render.prefilter import prefiltered_mips
from skyscatter.render.radiance_grid import sky_radiance_grid, surface_irradiance_grid
from skyscatter.render.radiance_hdr import hdr_writer
from skyscatter.render.scene import (
    SkyImage,
    Viewpoint,
    ground_viewpoint,
    orbit_viewpoint,
    render_sky,
    sun_direction,
)
from skyscatter.render.scene import without_ground as _without_ground
from skyscatter.render.sky_at_time import (
    Ephemeris,
    Observer,
    SkyObjects,
    eclipse_optics,
    ephemeris,
    render_sky_at,
)
from skyscatter.render.spectral_exr import FICHET2021_ATTRIBUTES, fichet2021_channel_name
from skyscatter.render.sphere_map import SphereMapCamera
from skyscatter.render.surfaces import Ground
from skyscatter.render.terrain import Heightfield, demo_mountains
from skyscatter.render.timelapse import write_frames
from skyscatter.render.video_io import VideoWriter
from skyscatter.spectrum.colour import into_gamut, rgb_space_chromaticities, xyz_to_rgb
from skyscatter.spectrum.grid import (
    COLOUR_RANGE_NM,
    DEFAULT_WAVELENGTH_BINS,
    MONOCHROMATIC_RANGE_NM,
    checked_data_wavelengths,
    checked_grid,
    wavelength_grid,
)
from skyscatter.sweep.assemble import grid_coordinates, grid_variables, time_coordinates
from skyscatter.sweep.plan import SweepPlan
from skyscatter.sweep.run import run_sweep
from skyscatter.sweep.store import ChunkStore, parts_folder
from skyscatter.transport.cache import TableCache
from skyscatter.transport.plane_irradiance import plane_irradiance, plane_normal
from skyscatter.transport.solvers import (
    SOLVERS,
    Solver,
    SolverOptions,
    SurfaceSolver,
    make_solver,
)
from skyscatter.validate.report import CaseResult, ValidationSettings
from skyscatter.validate.suite import CASES as VALIDATION_CASES
from skyscatter.validate.suite import ValidationRun, run_suite
from skyscatter.viewer import server as viewer_server_module
from skyscatter.viewer.server import ViewerServer, make_server
from skyscatter.viewer.sky_message import sky_message
from skyscatter.viewer.table_export import OWNED as EXPORT_FILES
from skyscatter.viewer.table_export import ExportedTables, ExportSettings
from skyscatter.viewer.table_export import export_tables as write_exported_tables
from skyscatter.viewer.table_service import TableService

if TYPE_CHECKING:  # imported when called: it imports matplotlib (with its Agg backend)
    from skyscatter.validate.technique_comparison import ComparisonResult

__all__ = [
    "COLOUR_RANGE_NM",
    "CUBE_LAYOUTS",
    "DEFAULT_WAVELENGTH_BINS",
    "EXR_CONTENTS",
    "MAX_FRAMES",
    "MAX_SAMPLES",
    "MAX_SCATTERING_ORDERS",
    "MAX_SIDE_PIXELS",
    "MONOCHROMATIC_RANGE_NM",
    "VALIDATION_CASES",
    "ValidationSettings",
    "AlbedoMap",
    "Clouds",
    "CubeMapCamera",
    "EquirectangularCamera",
    "FRAME_NAME",
    "FisheyeCamera",
    "FreeParameter",
    "Ground",
    "Heightfield",
    "ImageOptions",
    "Observer",
    "OctahedralCamera",
    "ParaboloidCamera",
    "PerspectiveCamera",
    "Retrieval",
    "SkyImage",
    "SkyObjects",
    "SolverOptions",
    "SphereMapCamera",
    "SweepResult",
    "check_image_options",
    "compare_techniques",
    "check_mip_chain",
    "check_render_cost",
    "demo_mountains",
    "describe_gas",
    "list_cloud_presets",
    "list_presets",
    "load_clouds",
    "load_atmosphere",
    "load_solver",
    "look_at_direction",
    "orbit_field_of_view_deg",
    "make_observer",
    "render",
    "render_at",
    "environment_light",
    "environment_series",
    "without_ground",
    "with_ground_albedo",
    "export_tables",
    "fit",
    "image_measurements",
    "measurement_rows",
    "irradiance_dataset",
    "irradiance_rows",
    "output_metadata",
    "radiance_dataset",
    "write_netcdf",
    "write_zarr",
    "save_image",
    "sky_ephemeris",
    "timelapse",
    "save_mip_chain",
    "sky_radiance_rows",
    "sun_distance_scale",
    "solver_options",
    "sun_direction",
    "sweep",
    "parse_values",
    "viewer_server",
    "viewpoint_at",
    "is_loopback",
    "parse_time",
    "run_validation",
    "serve_viewer",
    "wavelength_grid",
]

J2000_UTC = datetime.datetime(2000, 1, 1, 12, tzinfo=datetime.UTC)  # the clouds' epoch
# (2000-01-01 12:00 UTC, within 64 s of J2000.0 in TT: a fixed origin is all they need)

# The files of a time-lapse's frames folder: the folder holds these only, and is replaced whole
FRAME_NAME = re.compile(r"frame_[0-9]{5,}\.png")
# what a folder of `environment_series` holds
ENVMAP_NAME = re.compile(r"sky_[0-9]{5,}(_mip[0-9]+)?\.(exr|hdr)|light_[0-9]{5,}\.json|index\.json")


def solver_options(atmosphere: Atmosphere, *, orders: int | None = None, n_samples: int = 64,
                   cache_dir: str | Path | None = None, use_cache: bool = True,
                   force: bool = False,
                   progress: Callable[[int, int, str], None] | None = None,
                   log: Callable[[str], None] | None = None) -> SolverOptions:
    """Solver settings for `atmosphere`: `orders` defaults to its config's `[tables] orders`;
    tables are cached in `cache_dir` (default: `default_cache_directory()`) unless
    `use_cache` is False; `force` recomputes them. InputError for `orders` outside
    1-`MAX_SCATTERING_ORDERS` (the config's bound) or `n_samples` outside 1-`MAX_SAMPLES`."""
    _check_atmosphere(atmosphere)
    if orders is not None:
        orders = checked_integer("orders", orders, 1, MAX_SCATTERING_ORDERS)
    return SolverOptions(
        n_samples=checked_integer("n_samples", n_samples, 1, MAX_SAMPLES),
        orders=atmosphere.scattering_orders if orders is None else orders,
        cache=TableCache(cache_dir) if use_cache else None, force=force, progress=progress,
        log=log)


def load_solver(atmosphere: Atmosphere, wavelengths_nm: Sequence[float] | None = None,
                solver: str = "lut", options: SolverOptions | None = None,
                monochromatic: bool = False) -> Solver:
    """A solver (`transport.solvers.SOLVERS`) of `atmosphere` on `wavelengths_nm` (default:
    16 bins over 360-830 nm; `monochromatic`: 1 nm cells at each wavelength, as
    `sky_radiance_rows`). With the "lut" solver the tables come from the cache or are
    precomputed once and stored (`options`, default `solver_options(atmosphere)`).
    InputError for wavelengths outside the shipped data (`spectrum.grid.checked_data_wavelengths`:
    360-830 nm for images, 280.5-1690 nm `monochromatic`)."""
    _check_atmosphere(atmosphere)
    wavelengths = _checked_wavelength_list(wavelengths_nm, monochromatic)
    profile = atmosphere.optical_profile(wavelengths, monochromatic=monochromatic)
    return make_solver(solver, profile, options or solver_options(atmosphere))


def _checked_wavelength_list(wavelengths_nm: Sequence[float] | None,
                             monochromatic: bool) -> np.ndarray:
    """The wavelengths of a solver: the default bins, or a checked non-empty 1-D list."""
    if wavelengths_nm is None:
        return wavelength_grid(DEFAULT_WAVELENGTH_BINS)
    checked_array("wavelengths_nm", wavelengths_nm)  # numbers, finite
    if monochromatic:
        wavelengths = checked_data_wavelengths(np.atleast_1d(wavelengths_nm), True)
        if wavelengths.ndim != 1 or wavelengths.size == 0:
            raise InputError(f"wavelengths_nm = {wavelengths_nm!r} is not allowed: a non-empty "
                             "list of wavelengths [nm]", key="wavelengths_nm", value=wavelengths_nm,
                             allowed="a non-empty list of wavelengths [nm]")
        return wavelengths
    return checked_grid(checked_data_wavelengths(wavelengths_nm))


def check_render_cost(camera: Camera, wavelengths_nm: Sequence[float] | None = None,
                      solver: str = "lut", *, n_samples: int = 64, allow_large: bool = False,
                      frames: int = 1) -> None:
    """InputError when rendering `frames` images of `camera` on `wavelengths_nm` (default 16)
    would need more memory than this computer has, or with the "single" and "montecarlo"
    solvers more than an hour (`render.budget`); nothing with `allow_large`. `render`,
    `render_at` and `timelapse` call it before any work."""
    _check_camera(camera)
    n_wl = DEFAULT_WAVELENGTH_BINS if wavelengths_nm is None else int(np.size(wavelengths_nm))
    width, height = int(camera.width), int(camera.height)
    what = f"a {width} x {height}-pixel image at {n_wl} wavelengths"
    if frames > 1:
        what = f"{frames} frames of {what[2:]}"
    check_cost(what, image_memory_bytes(width, height, n_wl), float(width) * height * frames,
               n_wl, solver=solver, n_samples=n_samples, allow_large=allow_large)


def _checked_engine(atmosphere: Atmosphere, camera: Camera, wavelengths_nm: Sequence[float] | None,
                    solver: str, options: SolverOptions | None, *, allow_large: bool,
                    clouds: Clouds | None, frames: int = 1) -> Solver:
    """The solver of a render of `frames` images by `camera`, after the checks that come
    before any work: the wavelengths, the cost (`check_render_cost`), clouds only with the
    table solver ("lut")."""
    wavelengths = _checked_wavelength_list(wavelengths_nm, False)
    check_render_cost(camera, wavelengths, solver, n_samples=_samples(options),
                      allow_large=allow_large, frames=frames)
    if clouds is not None and solver != "lut":
        raise InputError("clouds need the table solver (--solver lut)", key="solver",
                         value=solver, allowed="lut")
    return load_solver(atmosphere, wavelengths, solver, options)


def _check_atmosphere(atmosphere: Atmosphere) -> None:
    checked_instance("atmosphere", atmosphere, Atmosphere, "an Atmosphere",
                     ", e.g. load_atmosphere('earth')")


def sun_distance_scale(atmosphere: Atmosphere, sun_distance_m: float | None) -> float:
    """(d_config / d)^2: the factor by which a star at distance `sun_distance_m` [m] (a date's,
    `sky_ephemeris(...).sun.distance_m`) lights the planet more than at the config's distance
    (1 for None). Sky radiance and irradiance are linear in it; the tables are not recomputed."""
    if sun_distance_m is None:
        return 1.0
    distance = checked_number("sun_distance_m", sun_distance_m, 0.0, low_open=True)
    return atmosphere.planet.star.irradiance_scale_at(distance)


def _check_camera(camera: Camera) -> None:
    if not all(hasattr(camera, name) for name in ("width", "height", "directions",
                                                  "valid_mask", "pixel_solid_angles")):
        raise InputError(f"camera = {camera!r} is not allowed: a camera, e.g. FisheyeCamera(512)",
                         key="camera", value=camera, allowed="a Camera")


def _samples(options: SolverOptions | None) -> int:
    return 64 if options is None else options.n_samples


def render(atmosphere: Atmosphere, camera: Camera, sun_zenith_deg: float,
           sun_azimuth_deg: float = 180.0, altitude_m: float = 0.0, *,
           wavelengths_nm: Sequence[float] | None = None, solver: str = "lut",
           options: SolverOptions | None = None,
           progress: Callable[[int], None] | None = None,
           orbit_latitude_deg: float | None = None, orbit_longitude_deg: float = 0.0,
           ground: Ground | None = None, allow_large: bool = False,
           clouds: Clouds | None = None, cloud_time_s: float = 0.0,
           sun_disk: bool = True) -> SkyImage:
    """Render what `camera` sees from `altitude_m` [m] above the ground, with the sun at
    `sun_zenith_deg` and `sun_azimuth_deg` (from north towards east) in the observer's local
    frame. Spectral, on `wavelengths_nm` (default: 16 bins over 360-830 nm). With
    `orbit_latitude_deg` the camera hangs above that latitude/longitude (views from space;
    pitch -90 looks at the planet's centre); otherwise above the north pole. `ground` adds an
    albedo map and/or terrain (table solver). `clouds` (`load_clouds`) adds cloud layers as
    the wind has moved them `cloud_time_s` [s] after their initial state (table solver).
    Without `sun_disk` the sun's disk is left out (its light stays in the image's `sun`, for
    `environment_light`). `options`: `solver_options(atmosphere)` by
    default (the config's orders, tables cached). InputError, before any work, for a value
    out of range (`checks`) or an image too large (`check_render_cost`; `allow_large`)."""
    _check_atmosphere(atmosphere)
    sun = sun_direction(ZENITH_DEG.check("sun_zenith_deg", sun_zenith_deg),
                        ANGLE_DEG.check("sun_azimuth_deg", sun_azimuth_deg))
    ALTITUDE_M.check("altitude_m", altitude_m)
    if orbit_latitude_deg is not None:
        LATITUDE_DEG.check("orbit_latitude_deg", orbit_latitude_deg)
        ANGLE_DEG.check("orbit_longitude_deg", orbit_longitude_deg)
    # clouds are checked with their field (`_cloud_field`)
    engine = _checked_engine(atmosphere, camera, wavelengths_nm, solver, options,
                             allow_large=allow_large, clouds=None)
    viewpoint = viewpoint_at(altitude_m, engine.profile.bottom_radius_m, orbit_latitude_deg,
                             orbit_longitude_deg)
    return render_sky(engine, camera, viewpoint, sun, atmosphere.planet.star, progress=progress,
                      ground=ground, sun_disk=bool(sun_disk),
                      clouds=_cloud_field(clouds, engine, viewpoint, cloud_time_s, solver,
                                          camera=camera, place=(
                                              (0.0, 0.0) if orbit_latitude_deg is None
                                              else (orbit_latitude_deg, orbit_longitude_deg))))


def _cloud_field(clouds: Clouds | None, engine, viewpoint: Viewpoint, time_s: float,
                 solver: str, *, camera: Camera | None = None,
                 place: tuple[float, float] = (0.0, 0.0)) -> CloudField | None:
    """The field of `clouds` for this solver's wavelengths and planet, winds in the
    viewpoint's frame, coverage maps oriented for an observer at `place` (latitude,
    longitude [deg]; the CLI's default 0, 0 for undated views from the ground), the far
    field from `camera`'s pixel size; None without clouds. InputError unless the solver is
    "lut"."""
    if clouds is None:
        return None
    checked_instance("clouds", clouds, Clouds, "Clouds", " from load_clouds(name or path)")
    if solver != "lut":
        raise InputError("clouds need the table solver (--solver lut)", key="solver",
                         value=solver, allowed="lut")
    profile = engine.profile
    pixel = None
    if camera is not None:
        solid = camera.pixel_solid_angles()[camera.valid_mask()]
        pixel = float(np.sqrt(np.median(solid))) if solid.size else None
    return cloud_field(clouds, profile.bottom_radius_m, profile.wavelengths_nm,
                       to_world=viewpoint.to_world, time_s=time_s, latitude_deg=place[0],
                       longitude_deg=place[1], pixel_angle_rad=pixel)


def _seconds_since_j2000(observer: Observer) -> float:
    """The clouds' time of a dated render: seconds since 2000-01-01T12:00 UTC."""
    return (observer.time_utc - J2000_UTC).total_seconds()


def make_observer(time: str | datetime.datetime, latitude_deg: float, longitude_deg: float,
                  elevation_m: float = 0.0) -> Observer:
    """An `Observer` from an ISO 8601 time with a time zone (or an aware datetime), or a Mars
    Sol Date written "MSD 44795.9998" (Allison & McEwen 2000; `astro.mars_time`), latitude
    [deg, north +], longitude [deg, east +] and elevation above the ground [m], from -500 m
    to 1e7 m. InputError for a time without a zone or outside the years 1-9999 in UTC, or a
    place out of range."""
    if isinstance(time, str) and time.strip().upper().startswith("MSD"):
        when = utc_from_mars_sol_date(_mars_sol_date(time))
    elif isinstance(time, str):
        when = parse_time(time)
    elif isinstance(time, datetime.datetime) and time.utcoffset() is not None:
        when = check_utc(time, "time")
    else:
        raise InputError(f"time {time!r} needs a time zone, e.g. 2024-06-21T21:30+02:00",
                         key="time", value=time)
    latitude = LATITUDE_DEG.check("latitude_deg", latitude_deg)
    longitude = ANGLE_DEG.check("longitude_deg", longitude_deg)
    elevation = checked_number("elevation_m", elevation_m, -500.0, 1e7)
    return Observer(when, latitude, longitude, elevation)


def _mars_sol_date(text: str) -> float:
    """The number of "MSD 44795.9998" (also "MSD=...", "msd:...")."""
    number = text.strip()[3:].lstrip(" =:")
    try:
        value = float(number)
    except ValueError:
        raise InputError(f"time {text!r}: write a Mars Sol Date as 'MSD 44795.9998'",
                         key="time", value=text) from None
    return checked_number("Mars Sol Date", value, 0.0, 1e6)


def sky_ephemeris(atmosphere: Atmosphere, observer: Observer) -> Ephemeris:
    """Sun, moon and sky orientation for `observer` on the atmosphere's planet ([planet] body:
    Earth or Mars)."""
    return ephemeris(atmosphere.planet.body, observer)


def render_at(atmosphere: Atmosphere, camera: Camera, observer: Observer,
              objects: SkyObjects | None = None, *,
              wavelengths_nm: Sequence[float] | None = None, solver: str = "lut",
              options: SolverOptions | None = None,
              progress: Callable[[int], None] | None = None,
              orbit_altitude_m: float | None = None, ground: Ground | None = None,
              allow_large: bool = False, clouds: Clouds | None = None) -> SkyImage:
    """The whole sky for `observer` (`make_observer`): the atmosphere lit by the sun and the
    moon, the sun's and moon's disks, the stars (`objects`). The camera stands at the
    observer's elevation, or with `orbit_altitude_m` hangs that high above the observer's
    latitude/longitude (pitch -90 looks at the planet's centre). `clouds` drift with their
    wind from their initial state at J2000 (2000-01-01T12:00 UTC): the same time gives the
    same sky. Other arguments, and the InputError for bad ones, as `render`."""
    _check_atmosphere(atmosphere)
    _check_observer(observer)
    if orbit_altitude_m is not None:
        ALTITUDE_M.check("orbit_altitude_m", orbit_altitude_m)
    engine = _checked_engine(atmosphere, camera, wavelengths_nm, solver, options,
                             allow_large=allow_large, clouds=clouds)
    return _render_at(engine, atmosphere, camera, observer, objects or SkyObjects(), progress,
                      orbit_altitude_m, ground, clouds)


def _render_at(engine, atmosphere: Atmosphere, camera: Camera, observer: Observer,
               objects: SkyObjects, progress: Callable[[int], None] | None,
               orbit_altitude_m: float | None, ground: Ground | None,
               clouds: Clouds | None = None) -> SkyImage:
    sky = sky_ephemeris(atmosphere, observer)
    radius = engine.profile.bottom_radius_m
    if orbit_altitude_m is None:
        viewpoint = viewpoint_at(observer.elevation_m, radius)
    else:
        viewpoint = viewpoint_at(orbit_altitude_m, radius, observer.latitude_deg,
                                 observer.longitude_deg)
    optics = eclipse_optics(engine) if sky.moon is not None else None
    field = _cloud_field(clouds, engine, viewpoint, _seconds_since_j2000(observer), "lut",
                         camera=camera, place=(observer.latitude_deg, observer.longitude_deg))
    return render_sky_at(engine, camera, viewpoint, atmosphere.planet.star, sky,
                         objects=objects, progress=progress, ground=ground,
                         eclipse_optics=optics, clouds=field)


def _check_observer(observer: Observer) -> None:
    checked_instance("observer", observer, Observer, "an Observer",
                     " from make_observer(time, latitude_deg, longitude_deg)")


@dataclass(frozen=True)
class Timelapse:
    """What `timelapse` wrote: the video, the frames and each frame's exposure."""

    video: Path
    frames: list[Path]
    ev100: list[float]


def timelapse(atmosphere: Atmosphere, camera: Camera, times: Sequence[datetime.datetime],
              latitude_deg: float, longitude_deg: float, *, video_path: str | Path,
              frames_dir: str | Path, elevation_m: float = 0.0, fps: float = 24.0,
              objects: SkyObjects | None = None,
              wavelengths_nm: Sequence[float] | None = None, solver: str = "lut",
              options: SolverOptions | None = None, image: ImageOptions | None = None,
              compensation_ev: float = 1.0, operator: str = "aces", colour_space: str = "srgb",
              adaptation_time_s: float = 600.0,
              on_frame: Callable[[int, datetime.datetime, float], None] | None = None,
              orbit_altitude_m: float | None = None, allow_large: bool = False,
              clouds: Clouds | None = None, scheduler: str | None = None,
              workers: int | None = None) -> Timelapse:
    """Render the sky at each of `times` (aware datetimes) for one place and write the frames
    (PNG, `frames_dir/frame_00001.png` ...) and a video (`video_path`, .mp4 or .gif).

    The tables are computed (or loaded) once and serve every frame. The exposure follows the
    night-adapted meter (`night_adapted_exposure`) through a first-order low-pass of time
    constant `adaptation_time_s` in simulated time (`adapted_ev100`), so day, twilight and
    night flow into each other. With `objects.scintillation` (a random generator) the stars
    twinkle, a new draw each frame. `clouds` drift with their wind from frame to frame
    (`render_at`). `on_frame(index, time, ev100)` is called after each frame.

    With `scheduler` (a Dask scheduler's address) or `workers` (local worker processes) the
    frames are rendered on that Dask cluster (`dask_cluster`; the `[dask]` extra), a few
    ahead of the one being written, and the result is the serial run's (each worker builds
    the solver once, its tables from the cache; twinkling stars, which draw in frame order,
    are refused).

    `image` (an `ImageOptions`) holds the display choices in one object and, when given, is
    used instead of `compensation_ev`, `operator` and `colour_space` (kept for existing
    callers); a time-lapse meters each frame itself, so its `ev100` must be None, and its
    other fields do not apply.

    The outputs are checked before any work (`check_writable_file`, `check_writable_folder`:
    `frames_dir` may hold only frames, `FRAME_NAME`). The frames go to a new temporary folder
    and the video to a temporary file; only when all are done do they replace `frames_dir`
    and `video_path` together, so the folder holds exactly this run's frames and an
    interrupted run leaves the previous frames and video as they were.

    InputError before any work for bad arguments (as `render`), more than `MAX_FRAMES` times,
    `compensation_ev` outside [-40, 40], an `image` with a fixed `ev100` or a negative
    `adaptation_time_s`."""
    _check_atmosphere(atmosphere)
    if not 1 <= len(times) <= MAX_FRAMES:
        raise InputError(f"a time-lapse of {len(times)} times is not allowed: from 1 to "
                         f"{MAX_FRAMES} frames", key="times", value=len(times),
                         allowed=f"1 to {MAX_FRAMES} frames")
    image = _timelapse_image_options(image, compensation_ev, operator, colour_space)
    checked_number("adaptation_time_s", adaptation_time_s, 0.0, 1e9)
    if orbit_altitude_m is not None:
        ALTITUDE_M.check("orbit_altitude_m", orbit_altitude_m)
    VideoWriter(video_path, fps)  # checks the format and the rate before any work
    check_writable_file(video_path)
    check_writable_folder(frames_dir, FRAME_NAME)
    if Path(video_path).resolve().is_relative_to(Path(frames_dir).resolve()):
        raise InputError(f"the video {video_path} cannot go inside the frames folder "
                         f"{frames_dir}, which is replaced as a whole", key="video_path",
                         value=str(video_path))
    observers = [make_observer(t, latitude_deg, longitude_deg, elevation_m) for t in times]
    objects = objects or SkyObjects()
    on_cluster = scheduler is not None or workers is not None
    if on_cluster:
        import_distributed()
        if objects.scintillation is not None:
            raise InputError("twinkling stars draw their random numbers frame after frame: "
                             "leave --twinkle out on a cluster (--workers, --scheduler)",
                             key="twinkle", value="scintillation")
    engine = _checked_engine(atmosphere, camera, wavelengths_nm, solver, options,
                             allow_large=allow_large, clouds=clouds, frames=len(times))
    frames_dir = Path(frames_dir)
    frame_arguments = (atmosphere, camera, objects, orbit_altitude_m, clouds)

    with contextlib.ExitStack() as stack:
        if on_cluster:
            client = stack.enter_context(dask_client(scheduler, workers))
            # each worker builds the solver as a task (the tables from the cache, which
            # `_checked_engine` filled): a task Dask can run again if a worker dies, which
            # data sent by `client.scatter` is not
            shared = client.submit(load_solver, atmosphere,
                                   _checked_wavelength_list(wavelengths_nm, False), solver,
                                   _worker_options(options, atmosphere), pure=False)
            images = map_in_order(client, _timelapse_frame, observers, shared, *frame_arguments)

            def render_frame(observer: Observer) -> SkyImage:
                return next(images)
        else:
            def render_frame(observer: Observer) -> SkyImage:
                return _timelapse_frame(observer, engine, *frame_arguments)

        return _write_timelapse(render_frame, observers, video_path, fps, frames_dir,
                                image=image, adaptation_time_s=adaptation_time_s,
                                on_frame=on_frame)


def _worker_options(options: SolverOptions | None, atmosphere: Atmosphere) -> SolverOptions:
    """`options` (default: `solver_options(atmosphere)`) without the callbacks of this
    process (progress bars, log lines), for a Dask worker."""
    return replace(options or solver_options(atmosphere), progress=None, log=None)


def _timelapse_frame(observer: Observer, engine: Solver, atmosphere: Atmosphere, camera: Camera,
                     objects: SkyObjects, orbit_altitude_m: float | None,
                     clouds: Clouds | None) -> SkyImage:
    """One frame of `timelapse` (on a Dask worker, or here)."""
    return _render_at(engine, atmosphere, camera, observer, objects, None, orbit_altitude_m,
                      None, clouds)


def _write_timelapse(render_frame: Callable[[Observer], SkyImage], observers: list[Observer],
                     video_path: str | Path, fps: float, frames_dir: Path, *,
                     image: ImageOptions, adaptation_time_s: float,
                     on_frame: Callable[[int, datetime.datetime, float], None] | None
                     ) -> Timelapse:
    """The frames and video of `timelapse`, staged and committed together."""
    with staged_outputs() as stage, VideoWriter(video_path, fps, stage) as video:
        frames, exposures = write_frames(
            render_frame, observers, video, stage.folder(frames_dir), frames_dir,
            compensation_ev=image.compensation_ev, operator=image.operator,
            colour_space=image.colour_space, adaptation_time_s=adaptation_time_s,
            on_frame=on_frame)
    return Timelapse(Path(video_path), frames, exposures)


def _timelapse_image_options(image: ImageOptions | None, compensation_ev: float, operator: str,
                             colour_space: str) -> ImageOptions:
    """`image`, checked, or an `ImageOptions` of the separate arguments."""
    if image is None:
        return ImageOptions(compensation_ev=compensation_ev, operator=operator,
                            colour_space=colour_space)
    checked_instance("image", image, ImageOptions, "an ImageOptions")
    if image.ev100 is not None:
        raise InputError(f"image.ev100 = {image.ev100!r} is not allowed in a time-lapse, which "
                         "meters each frame: leave it None (use compensation_ev to shift the "
                         "exposure)", key="ev100", value=image.ev100, allowed="None")
    return image


def viewpoint_at(altitude_m: float, planet_radius_m: float, latitude_deg: float | None = None,
                 longitude_deg: float = 0.0) -> Viewpoint:
    """The camera's place: above the north pole (`latitude_deg` None, the frame of
    `ground_viewpoint`), or above (latitude, longitude) with that point's east-north-up
    frame. InputError for an altitude outside [-500, 1e12] m, a latitude outside [-90, 90],
    a non-finite longitude or a radius that is not finite and > 0."""
    if latitude_deg is None:
        return ground_viewpoint(altitude_m, planet_radius_m)
    return orbit_viewpoint(altitude_m, latitude_deg, longitude_deg, planet_radius_m)


def look_at_direction(viewpoint: Viewpoint, target_latitude_deg: float,
                      target_longitude_deg: float, target_altitude_m: float,
                      planet_radius_m: float) -> np.ndarray:
    """Unit direction (local east-north-up of `viewpoint`) from the camera towards the point
    `target_altitude_m` above (latitude, longitude)."""
    LATITUDE_DEG.check("target_latitude_deg", target_latitude_deg)
    ANGLE_DEG.check("target_longitude_deg", target_longitude_deg)
    target = orbit_viewpoint(target_altitude_m, target_latitude_deg, target_longitude_deg,
                             planet_radius_m).position_m
    offset = target - viewpoint.position_m
    distance = float(np.linalg.norm(offset))
    if not distance > 0.0:
        raise InputError("the look-at point is where the camera is; pick another point",
                         key="look_at", value=(target_latitude_deg, target_longitude_deg))
    return viewpoint.to_world.T @ (offset / distance)


def orbit_field_of_view_deg(altitude_m: float, planet_radius_m: float,
                            margin: float = 1.15) -> float:
    """Vertical field of view [deg] that frames the whole planet (with its atmosphere) seen
    from `altitude_m` above the ground: 2 asin(R / (R + h)) times `margin`."""
    ALTITUDE_M.check("altitude_m", altitude_m)
    checked_number("planet_radius_m", planet_radius_m, 0.0, None, low_open=True)
    checked_number("margin", margin, 0.0, 10.0, low_open=True)
    half = np.degrees(np.arcsin(planet_radius_m / (planet_radius_m + altitude_m)))
    return float(min(2.0 * half * margin, 170.0))


def check_image_options(operator: str = "aces", colour_space: str = "srgb",
                        exr_content: str = "rgb",
                        png_path: str | Path | BinaryIO | None = None,
                        exr_path: str | Path | None = None, *,
                        options: ImageOptions | None = None) -> None:
    """Raise InputError for an unknown tone-mapping operator, colour space or EXR content
    (`ImageOptions`; given `options`, checked when it was made, the first three arguments are
    not used), and for output paths that cannot be written (a suffix other than
    .png/.jpg/.jpeg for the display image or .exr/.hdr for the linear image, a .hdr of other
    than RGB, a directory, a read-only file or folder; see `output_files.check_writable_file`),
    so that a caller can reject them before rendering; `save_image` makes the same checks."""
    if options is None:
        options = ImageOptions(operator=operator, colour_space=colour_space,
                               exr_content=exr_content)
    _check_image_paths(png_path, exr_path, options.exr_content)


def _check_image_paths(png_path: str | Path | BinaryIO | None,
                       exr_path: str | Path | None, exr_content: str) -> None:
    if png_path is not None and not hasattr(png_path, "write"):
        display_format(png_path)
        check_writable_file(png_path)
    if exr_path is not None:
        if Path(exr_path).suffix.lower() not in (".exr", ".hdr"):
            raise InputError(f"cannot write a linear image as {str(exr_path)!r}: name it .exr "
                             "(OpenEXR) or .hdr (Radiance)", key="exr_path",
                             value=str(exr_path), allowed=".exr, .hdr")
        if Path(exr_path).suffix.lower() == ".hdr" and exr_content != "rgb":
            raise InputError(f"a Radiance .hdr holds RGB, not {exr_content}: name the file "
                             ".exr for that", key="exr_content", value=exr_content,
                             allowed="rgb")
        check_writable_file(exr_path)


# the cameras whose images hold the whole sphere (environment_light)
_WHOLE_SPHERE_CAMERAS = (CubeMapCamera, OctahedralCamera, EquirectangularCamera, SphereMapCamera,
                         ParaboloidCamera)


def _check_whole_sphere(camera: Camera) -> None:
    if not isinstance(camera, _WHOLE_SPHERE_CAMERAS):
        names = ", ".join(kind.__name__ for kind in _WHOLE_SPHERE_CAMERAS)
        raise InputError("the light of a sky needs an image of the whole sphere: render it "
                         f"with a {names} (--camera cubemap, octahedral, panorama, sphere or "
                         "paraboloid)", key="camera", value=camera, allowed=names)


def environment_light(image: SkyImage, camera: Camera, colour_space: str = "srgb", *,
                      balance_to_light: bool = False) -> dict:
    """The sun as a directional light (direction, illuminance [lux], linear RGB, angular
    radius) and the diffuse irradiance of the rest of the sky as 9 spherical-harmonic
    coefficients per channel (`render.environment_light`), from an image of the whole sphere
    rendered by `camera` (a `CubeMapCamera`, `OctahedralCamera`, `EquirectangularCamera`,
    `SphereMapCamera` or `ParaboloidCamera`), in the EXR's units and `colour_space`; a
    JSON-ready dict. InputError for a camera that does not see the whole sphere."""
    checked_instance("image", image, SkyImage, "a SkyImage", " from render or render_at")
    _check_whole_sphere(camera)
    check_image_options(colour_space=colour_space)
    directions, _ = camera.directions()
    return sky_light(image, directions, camera.pixel_solid_angles(), colour_space,
                     balance_to_light)


def save_image(image: SkyImage, png_path: str | Path | BinaryIO | None = None,
               exr_path: str | Path | None = None, *, ev100: float | None = None,
               compensation_ev: float = 1.0, operator: str = "aces",
               colour_space: str = "srgb", balance_to_light: bool = False,
               exr_content: str = "rgb", adapt_to_night: bool = False,
               options: ImageOptions | None = None) -> float:
    """Write a tone-mapped 8-bit PNG (or JPEG: `png_path` named .jpg/.jpeg; or a PNG to a
    binary stream such as `sys.stdout.buffer`) and/or a linear float32 EXR; returns the EV100
    used. Both files are written to temporaries first and replace the old ones together, so a
    failure in either leaves both old files as they were (`output_files.staged_outputs`).

    EXR contents: "rgb" (linear `colour_space`, 1.0 = 1 cd m^-2 of luminance, colours outside
    the space's gamut desaturated into it at constant luminance, `spectrum.colour.into_gamut`,
    so no channel is negative; the header's standard `chromaticities` name the space's
    primaries and white, `whiteLuminance` is 1),
    "luminance" (Y [cd m^-2]), "spectral" (one channel per wavelength [W m^-2 sr^-1 nm^-1])
    or "spectral-fichet2021" (the spectra named and tagged as Fichet et al. 2021 lay them
    out, `render.spectral_exr`, with the "rgb" channels beside them).
    `ev100=None` picks the exposure from the sky pixels (geometric-mean metering), or for
    views from space from the starlight (incident-light metering: sunlit white is white);
    `adapt_to_night` meters night skies as night (`night_adapted_exposure`: darker than a
    daylight grey, the exposure returned includes that shift). `options` (an `ImageOptions`)
    holds these choices in one object and, when given, is used instead of `ev100` ...
    `adapt_to_night`. InputError for an `ev100` or `compensation_ev` outside [-40, 40]
    (`checks.EV`) or an unknown option."""
    checked_instance("image", image, SkyImage, "a SkyImage", " from render or render_at")
    if options is None:
        options = ImageOptions(ev100=ev100, compensation_ev=compensation_ev, operator=operator,
                               colour_space=colour_space, balance_to_light=balance_to_light,
                               exr_content=exr_content, adapt_to_night=adapt_to_night)
    else:
        checked_instance("options", options, ImageOptions, "an ImageOptions")
    _check_image_paths(png_path, exr_path, options.exr_content)
    colour_space, exr_content = options.colour_space, options.exr_content
    xyz = image.xyz(options.balance_to_light)
    ev100 = options.ev100
    if ev100 is None:
        ev100 = metered_ev100(image, xyz, options.adapt_to_night)
    linear = xyz_to_rgb(xyz, colour_space)
    stream = png_path if hasattr(png_path, "write") else None
    with staged_outputs() as stage:
        if png_path is not None:
            write = display_image_writer(
                display_rgb8(linear, image.valid, ev100, options.compensation_ev,
                             options.operator),
                {"Software": "skyscatter", "EV100": f"{ev100:.3f}", "ColourSpace": colour_space},
                "PNG" if stream is not None else display_format(png_path),
                colour_space=colour_space)
            if stream is None:
                stage.write(png_path, write)
        if exr_path is not None and Path(exr_path).suffix.lower() == ".hdr":
            stage.write(exr_path, hdr_writer(into_gamut(linear, colour_space),
                                             rgb_space_chromaticities(colour_space)))
        elif exr_path is not None:
            layout = {}
            if exr_content == "rgb":
                data, names = into_gamut(linear, colour_space), ("R", "G", "B")
            elif exr_content == "luminance":
                data, names = xyz[..., 1:2], ("Y",)
            elif exr_content == "spectral":
                data = image.spectral
                names = tuple(f"radiance_{w:07.2f}nm" for w in image.wavelengths_nm)
            else:  # spectral-fichet2021: the spectra and an RGB preview
                data = np.concatenate([into_gamut(linear, colour_space), image.spectral], axis=-1)
                names = ("R", "G", "B", *map(fichet2021_channel_name, image.wavelengths_nm))
                layout = FICHET2021_ATTRIBUTES
            rgb = exr_content in ("rgb", "spectral-fichet2021")
            stage.write(exr_path, exr_writer(
                data.astype(np.float32), names,
                {"skyscatter_units": EXR_UNITS[exr_content],
                 "skyscatter_colour_space": colour_space, **layout},
                chromaticities=rgb_space_chromaticities(colour_space) if rgb else None,
                white_luminance=1.0 if exr_content != "spectral" else None))
    if stream is not None:
        write(stream)
        stream.flush()
    return float(ev100)


MAX_MIP_LEVELS = 16
MAX_MIP_FACE = 256  # level 1 sums 9 face^4 texel pairs: 11 s at 128, 16 times that at 256


def _mip_chain_paths(exr_path: str | Path, levels: int) -> list[Path]:
    """Where `save_mip_chain` writes levels 1 to `levels` - 1: beside `exr_path`, named
    `<stem>_mip<k><suffix>` (sky.exr -> sky_mip1.exr, ...)."""
    path = Path(exr_path)
    return [path.with_name(f"{path.stem}_mip{k}{path.suffix}") for k in range(1, levels)]


def check_mip_chain(camera: Camera, levels: int, exr_path: str | Path | None,
                    exr_content: str = "rgb") -> None:
    """InputError, before any work, unless a mip chain of `levels` can be made of `camera`'s
    image and written beside `exr_path` (`save_mip_chain`)."""
    checked_integer("mips", levels, 2, MAX_MIP_LEVELS)
    if not isinstance(camera, CubeMapCamera):
        raise InputError("a prefiltered mip chain (--mips) is made of cube maps: add --camera "
                         "cubemap", key="mips", value=levels)
    if exr_path is None or exr_content != "rgb":
        raise InputError("the mip chain (--mips) is written beside the linear RGB image: add "
                         "--exr sky.exr (or .hdr) with --exr-content rgb", key="mips",
                         value=levels)
    step = 1 << (levels - 1)
    if camera.face % step or camera.face > MAX_MIP_FACE:
        raise InputError(f"{levels} mip levels halve the face {levels - 1} times: --size must "
                         f"be a multiple of {step} and at most {MAX_MIP_FACE}, got {camera.face}",
                         key="size", value=camera.face,
                         allowed=f"multiples of {step} up to {MAX_MIP_FACE}")
    for path in _mip_chain_paths(exr_path, levels):
        check_writable_file(path)


def save_mip_chain(image: SkyImage, camera: CubeMapCamera, exr_path: str | Path, levels: int,
                   *, options: ImageOptions | None = None) -> list[Path]:
    """Write the specular mip chain of a cube map (`render.prefilter`: GGX-prefiltered, Karis
    2013, roughness k / (levels - 1) at level k, faces halved at each level): levels 1 to
    `levels` - 1 beside `exr_path` (`_mip_chain_paths`; level 0 is the image itself, which
    `save_image` writes there), as EXR or Radiance .hdr like it, in its units (1.0 =
    1 cd m^-2) and `options`' colour space. Returns the paths written. InputError as
    `check_mip_chain`."""
    checked_instance("image", image, SkyImage, "a SkyImage", " from render or render_at")
    options = ImageOptions() if options is None else options
    check_mip_chain(camera, levels, exr_path, options.exr_content)
    space = options.colour_space
    rgb = into_gamut(xyz_to_rgb(image.xyz(options.balance_to_light), space), space)
    chain = prefiltered_mips(np.where(image.valid[..., None], rgb, 0.0), camera, levels)
    paths = _mip_chain_paths(exr_path, levels)
    with staged_outputs() as stage:
        for path, level in zip(paths, chain[1:], strict=True):
            if path.suffix.lower() == ".hdr":
                stage.write(path, hdr_writer(level, rgb_space_chromaticities(space)))
            else:
                stage.write(path, exr_writer(
                    level.astype(np.float32), ("R", "G", "B"),
                    {"skyscatter_units": EXR_UNITS["rgb"], "skyscatter_colour_space": space},
                    chromaticities=rgb_space_chromaticities(space), white_luminance=1.0))
    return paths


def environment_series(atmosphere: Atmosphere, camera: Camera,
                       times: Sequence[datetime.datetime], latitude_deg: float,
                       longitude_deg: float, *, out_dir: str | Path, elevation_m: float = 0.0,
                       suffix: str = ".exr", mips: int | None = None,
                       objects: SkyObjects | None = None,
                       wavelengths_nm: Sequence[float] | None = None, solver: str = "lut",
                       options: SolverOptions | None = None, image: ImageOptions | None = None,
                       on_frame: Callable[[int, datetime.datetime], None] | None = None,
                       allow_large: bool = False, clouds: Clouds | None = None,
                       black_ground: bool = False) -> dict:
    """Environment maps of the sky at each of `times` (aware datetimes) for one place, as
    `render_at` sees it with a camera of the whole sphere (`environment_light`'s): in
    `out_dir`, `sky_00001.exr` ... (or `.hdr`: `suffix`; linear RGB as `save_image` writes
    it, `image` for the colour space), `light_00001.json` ... (`environment_light`), with
    `mips` the mip chain of each (`save_mip_chain`), and `index.json`: the place, the camera
    and, per time, its files and the sun (direction in the map's axes, elevation and azimuth
    [deg], illuminance [lux]). The tables serve every time. The folder is checked before any
    work and replaced as a whole when every map is written (as `timelapse`'s frames). Returns
    the index. `on_frame(index, time)` is called after each map. With `black_ground` the maps
    are black below the horizon (`without_ground`). InputError before any work
    for bad arguments (as `render_at`, `check_mip_chain`) or more than `MAX_FRAMES` times."""
    _check_atmosphere(atmosphere)
    if not 1 <= len(times) <= MAX_FRAMES:
        raise InputError(f"a series of {len(times)} times is not allowed: from 1 to "
                         f"{MAX_FRAMES} maps", key="times", value=len(times),
                         allowed=f"1 to {MAX_FRAMES} maps")
    _check_whole_sphere(camera)
    if suffix not in (".exr", ".hdr"):
        raise InputError(f"environment maps are .exr or .hdr files, not {suffix!r}",
                         key="suffix", value=suffix, allowed=".exr, .hdr")
    image = ImageOptions() if image is None else image
    check_image_options(colour_space=image.colour_space)
    out_dir = Path(out_dir)
    if mips is not None:
        check_mip_chain(camera, mips, out_dir / f"sky_00001{suffix}", image.exr_content)
    check_writable_folder(out_dir, ENVMAP_NAME)
    observers = [make_observer(t, latitude_deg, longitude_deg, elevation_m) for t in times]
    engine = _checked_engine(atmosphere, camera, wavelengths_nm, solver, options,
                             allow_large=allow_large, clouds=clouds, frames=len(times))
    entries = []
    with staged_outputs() as stage:
        folder = stage.folder(out_dir)
        for number, observer in enumerate(observers, start=1):
            sky = _render_at(engine, atmosphere, camera, observer, objects or SkyObjects(),
                             None, None, None, clouds)
            if black_ground:
                sky = without_ground(sky, camera, atmosphere, elevation_m)
            names = {"map": f"sky_{number:05d}{suffix}", "light": f"light_{number:05d}.json"}
            save_image(sky, exr_path=folder / names["map"], options=image)
            light = environment_light(sky, camera, image.colour_space,
                                      balance_to_light=image.balance_to_light)
            (folder / names["light"]).write_text(json.dumps(light, indent=1, allow_nan=False)
                                                 + "\n", encoding="utf-8")
            if mips is not None:
                names["mips"] = [path.name for path in save_mip_chain(
                    sky, camera, folder / names["map"], mips, options=image)]
            entries.append({"time": observer.time_utc.isoformat(), **names,
                            "sun": _sun_entry(light)})
            if on_frame is not None:
                on_frame(number - 1, observer.time_utc)
        index = {"place": {"latitude_deg": latitude_deg, "longitude_deg": longitude_deg,
                           "elevation_m": elevation_m},
                 "camera": type(camera).__name__,
                 **({"cube_layout": camera.layout} if isinstance(camera, CubeMapCamera)
                    else {}),
                 "colour_space": image.colour_space,
                 "units": {"map": EXR_UNITS["rgb"], "sun.illuminance": "lux",
                           "sun.direction": "unit vector: x east, y up, z south",
                           "sun.elevation_deg": "deg", "sun.azimuth_deg": "deg, from north "
                           "towards east"},
                 "maps": entries}
        (folder / "index.json").write_text(json.dumps(index, indent=1, allow_nan=False)
                                           + "\n", encoding="utf-8")
    return index


def without_ground(image: SkyImage, camera: Camera, atmosphere: Atmosphere,
                   altitude_m: float = 0.0) -> SkyImage:
    """`image`, as `camera` saw it from `altitude_m` [m] above `atmosphere`'s ground, black
    wherever the view meets the planet (the ground and the air in front of it): an environment
    map whose lower half an engine draws itself (`render --ground black`)."""
    _check_atmosphere(atmosphere)
    _check_camera(camera)
    radius = atmosphere.planet.radius_m
    return _without_ground(image, camera, radius + ALTITUDE_M.check("altitude_m", altitude_m),
                           radius)


def _sun_entry(light: dict) -> dict | None:
    """The sun of a light file for the series index: its direction (x east, y up, z south),
    elevation and azimuth [deg] and illuminance [lux]; None without a sun."""
    sun = light.get("sun")
    if sun is None:
        return None
    x, y, z = sun["direction"]
    return {"direction": sun["direction"],
            "elevation_deg": round(math.degrees(math.asin(max(-1.0, min(1.0, y)))), 4),
            "azimuth_deg": round(math.degrees(math.atan2(x, -z)) % 360.0, 4),
            "illuminance": sun["illuminance"]}


def sky_radiance_rows(atmosphere: Atmosphere, sun_zeniths_deg: Sequence[float],
                      view_zeniths_deg: Sequence[float], relative_azimuths_deg: Sequence[float],
                      wavelengths_nm: Sequence[float], *, altitude_m: float = 0.0,
                      solver: str = "lut", options: SolverOptions | None = None,
                      allow_large: bool = False,
                      sun_distance_m: float | None = None) -> list[dict[str, float]]:
    """Diffuse sky radiance for every combination of the inputs, one dict per row with the keys
    sun_zenith_deg, view_zenith_deg, relative_azimuth_deg, wavelength_nm, radiance
    [W m^-2 sr^-1 nm^-1] and toa_irradiance [W m^-2 nm^-1], plus standard_error of the radiance
    for the Monte Carlo solver. Relative azimuth 0 looks towards the sun. Each wavelength is
    monochromatic (a 1 nm cell), within 280.5-1690 nm. `options`: `solver_options(atmosphere)`
    by default. `sun_distance_m`: the star that far (a date's) instead of the config's
    distance (`sun_distance_scale`). InputError, before any work, for an empty list, a value
    out of range (zenith angles [0, 180], finite azimuths) or a table too large
    (`render.budget`; `allow_large`)."""
    _check_atmosphere(atmosphere)
    scale = sun_distance_scale(atmosphere, sun_distance_m)
    sun_zeniths_deg = _angle_list("sun_zeniths_deg", sun_zeniths_deg, ZENITH_DEG)
    view_zeniths_deg = _angle_list("view_zeniths_deg", view_zeniths_deg, ZENITH_DEG)
    relative_azimuths_deg = _angle_list("relative_azimuths_deg", relative_azimuths_deg,
                                        ANGLE_DEG)
    ALTITUDE_M.check("altitude_m", altitude_m)
    wavelengths = _checked_wavelength_list(wavelengths_nm, True)
    rays = sun_zeniths_deg.size * view_zeniths_deg.size * relative_azimuths_deg.size
    check_cost(f"a radiance table of {rays * wavelengths.size} rows",
               rays * wavelengths.size * BYTES_PER_ROW, rays, wavelengths.size, solver=solver,
               n_samples=_samples(options), allow_large=allow_large)
    engine = load_solver(atmosphere, wavelengths, solver, options, monochromatic=True)
    profile = engine.profile
    radiance, error = sky_radiance_grid(engine, altitude_m, sun_zeniths_deg, view_zeniths_deg,
                                        relative_azimuths_deg)
    rows = []
    for (s, sun_zenith), (i, vz), (j, az) in itertools.product(
            enumerate(sun_zeniths_deg), enumerate(view_zeniths_deg),
            enumerate(relative_azimuths_deg)):
        for k, wavelength in enumerate(profile.wavelengths_nm):
            row = {"sun_zenith_deg": float(sun_zenith), "view_zenith_deg": float(vz),
                   "relative_azimuth_deg": float(az), "wavelength_nm": float(wavelength),
                   "radiance": float(scale * radiance[s, i, j, k]),
                   "toa_irradiance": float(scale * profile.toa_irradiance[k])}
            if error is not None:
                row["standard_error"] = float(scale * error[s, i, j, k])
            rows.append(row)
    return rows


def irradiance_rows(atmosphere: Atmosphere, sun_zeniths_deg: Sequence[float],
                    wavelengths_nm: Sequence[float], *, altitude_m: float = 0.0,
                    solver: str = "lut", options: SolverOptions | None = None,
                    transmittance: bool = False, tilt_deg: float | None = None,
                    plane_azimuth_deg: float = 180.0, sun_azimuth_deg: float = 180.0,
                    sun_distance_m: float | None = None) -> list[dict[str, float]]:
    """Spectral irradiance at the observer for each sun zenith angle and wavelength, one dict
    per row with the keys sun_zenith_deg, wavelength_nm, direct_normal (the sun's direct light
    on a surface facing it, its hidden part left out), diffuse_horizontal (the sky's light on a
    horizontal surface), global_horizontal (their sum on the horizontal: direct_normal cos
    (sun zenith) + diffuse_horizontal), each [W m^-2 nm^-1], and toa_irradiance
    [W m^-2 nm^-1]. Monochromatic wavelengths as `sky_radiance_rows`. `transmittance` adds
    direct_transmittance [-] (direct_normal / toa_irradiance). `tilt_deg` adds a plane tilted
    that far from the horizontal, facing `plane_azimuth_deg` (from north towards east; the
    sun at `sun_azimuth_deg`): direct_transmittance, sun_azimuth_deg, tilt_deg,
    plane_azimuth_deg, then plane_direct, plane_sky_diffuse (from the solver's sky radiance
    distribution), plane_ground_reflected and plane_global [W m^-2 nm^-1]
    (`transport.plane_irradiance`). `sun_distance_m` as `sky_radiance_rows` (the
    transmittances stay). InputError, before any work, for an empty list, a value out of
    range, or a solver that does not light surfaces (the Monte Carlo's)."""
    _check_atmosphere(atmosphere)
    scale = sun_distance_scale(atmosphere, sun_distance_m)
    sun_zeniths_deg = _angle_list("sun_zeniths_deg", sun_zeniths_deg, ZENITH_DEG)
    ALTITUDE_M.check("altitude_m", altitude_m)
    ANGLE_DEG.check("sun_azimuth_deg", sun_azimuth_deg)
    normal = None
    if tilt_deg is not None:
        # in the sun's frame (sun at azimuth 0), where the horizontal values are computed:
        # the planet's atmosphere is the same in every azimuth
        normal = plane_normal(ZENITH_DEG.check("tilt_deg", tilt_deg),
                              ANGLE_DEG.check("plane_azimuth_deg", plane_azimuth_deg)
                              - sun_azimuth_deg)
    wavelengths = _checked_wavelength_list(wavelengths_nm, True)
    engine = load_solver(atmosphere, wavelengths, solver, options, monochromatic=True)
    if not isinstance(engine, SurfaceSolver):
        raise InputError(f"the {solver!r} solver does not give irradiance; use lut or single",
                         key="solver", value=solver, allowed="lut, single")
    profile = engine.profile
    direct_normals, diffuses, globals_ = surface_irradiance_grid(engine, altitude_m,
                                                                 sun_zeniths_deg)
    rows = []
    for sun_zenith, direct_normal, diffuse, global_ in zip(sun_zeniths_deg, direct_normals,
                                                           diffuses, globals_, strict=True):
        plane = (None if normal is None else
                 plane_irradiance(engine, sun_direction(sun_zenith, 0.0), normal, altitude_m))
        for k, wavelength in enumerate(profile.wavelengths_nm):
            row = {"sun_zenith_deg": float(sun_zenith), "wavelength_nm": float(wavelength),
                   "direct_normal": float(scale * direct_normal[k]),
                   "diffuse_horizontal": float(scale * diffuse[k]),
                   "global_horizontal": float(scale * global_[k]),
                   "toa_irradiance": float(scale * profile.toa_irradiance[k])}
            if transmittance or plane is not None:
                row["direct_transmittance"] = float(direct_normal[k] / profile.toa_irradiance[k])
            if plane is not None:
                row.update({"sun_azimuth_deg": float(sun_azimuth_deg),
                            "tilt_deg": float(tilt_deg),
                            "plane_azimuth_deg": float(plane_azimuth_deg),
                            "plane_direct": float(scale * plane.beam[k]),
                            "plane_sky_diffuse": float(scale * plane.sky_diffuse[k]),
                            "plane_ground_reflected": float(scale * plane.ground_reflected[k]),
                            "plane_global": float(scale * plane.total[k])})
            rows.append(row)
    return rows


def radiance_dataset(atmosphere: Atmosphere, sun_zeniths_deg: Sequence[float],
                     view_zeniths_deg: Sequence[float], azimuths_deg: Sequence[float],
                     wavelengths_nm: Sequence[float], *, altitude_m: float = 0.0,
                     solver: str = "lut", options: SolverOptions | None = None,
                     allow_large: bool = False, sun_distance_m: float | None = None):
    """`sky_radiance_rows` as an `xarray.Dataset` (`datasets.rows_dataset`): radiance (and
    standard_error) over (sun_zenith, view_zenith, azimuth relative to the sun, wavelength),
    toa_irradiance over wavelength, with CF `units`/`long_name` and the run's
    `output_metadata` as global attributes; `write_netcdf` saves it. InputError as
    `sky_radiance_rows`, and naming the `[science]` extra when xarray is missing."""
    import_xarray()  # before any work
    rows = sky_radiance_rows(atmosphere, sun_zeniths_deg, view_zeniths_deg, azimuths_deg,
                             wavelengths_nm, altitude_m=altitude_m, solver=solver,
                             options=options, allow_large=allow_large,
                             sun_distance_m=sun_distance_m)
    inputs = (sun_zeniths_deg, view_zeniths_deg, azimuths_deg, wavelengths_nm)
    geometry = _distance_geometry({"altitude_m": float(altitude_m)}, sun_distance_m)
    metadata = output_metadata(atmosphere, list(rows[0]), wavelengths_nm, solver=solver,
                               options=options, geometry=geometry)
    return rows_dataset(rows, {"sun_zenith_deg": "sun_zenith", "view_zenith_deg": "view_zenith",
                               "relative_azimuth_deg": "azimuth", "wavelength_nm": "wavelength"},
                        [np.size(values) for values in inputs], metadata,
                        reduced={"toa_irradiance": ("wavelength",)})


def irradiance_dataset(atmosphere: Atmosphere, sun_zeniths_deg: Sequence[float],
                       wavelengths_nm: Sequence[float], *, altitude_m: float = 0.0,
                       solver: str = "lut", options: SolverOptions | None = None,
                       tilt_deg: float | None = None, plane_azimuth_deg: float = 180.0,
                       sun_azimuth_deg: float = 180.0, sun_distance_m: float | None = None):
    """`irradiance_rows` (with direct_transmittance, and the plane's columns for `tilt_deg`) as
    an `xarray.Dataset` over (sun_zenith, wavelength); toa_irradiance over wavelength, the
    plane's angles scalar coordinates; attributes as `radiance_dataset`."""
    import_xarray()
    rows = irradiance_rows(atmosphere, sun_zeniths_deg, wavelengths_nm, altitude_m=altitude_m,
                           solver=solver, options=options, transmittance=True,
                           tilt_deg=tilt_deg, plane_azimuth_deg=plane_azimuth_deg,
                           sun_azimuth_deg=sun_azimuth_deg, sun_distance_m=sun_distance_m)
    geometry = _distance_geometry({"altitude_m": float(altitude_m)}, sun_distance_m)
    metadata = output_metadata(atmosphere, list(rows[0]), wavelengths_nm, solver=solver,
                               options=options, geometry=geometry)
    return rows_dataset(rows, {"sun_zenith_deg": "sun_zenith", "wavelength_nm": "wavelength"},
                        [np.size(sun_zeniths_deg), np.size(wavelengths_nm)], metadata,
                        reduced={"toa_irradiance": ("wavelength",), "sun_azimuth_deg": (),
                                 "tilt_deg": (), "plane_azimuth_deg": ()}
                        ).rename({name: name.removesuffix("_deg") for name in
                                  ("sun_azimuth_deg", "tilt_deg", "plane_azimuth_deg")
                                  if name in rows[0]})


def _distance_geometry(geometry: dict, sun_distance_m: float | None) -> dict:
    """`geometry` with the star's distance of the run [m] where a date set it."""
    return geometry if sun_distance_m is None else {**geometry,
                                                    "sun_distance_m": float(sun_distance_m)}


@dataclass(frozen=True)
class SweepResult:
    """What `sweep` made: the `dataset` (`xarray.Dataset`, docs/sweep.md), the file or Zarr
    store it was written to (None: not written), and how many chunks were `computed` now and
    `reused` from the chunk store of an earlier, interrupted run."""

    dataset: object
    output: Path | None
    computed: int
    reused: int


def sweep(config: str | Path, values: Mapping[str, str | Sequence[object]] | None = None,
          sun_zeniths_deg: Sequence[float] | None = None,
          view_zeniths_deg: Sequence[float] = (0.0,),
          relative_azimuths_deg: Sequence[float] = (0.0,), *,
          times: Sequence[str | datetime.datetime] | None = None,
          latitude_deg: float | None = None, longitude_deg: float | None = None,
          wavelengths_nm: Sequence[float] = (440.0, 550.0, 680.0),
          output_path: str | Path | None = None, altitude_m: float = 0.0, solver: str = "lut",
          orders: int | None = None, n_samples: int = 64, seed: int = 0,
          cache_dir: str | Path | None = None, use_cache: bool = True,
          scheduler: str | None = None, workers: int | None = None,
          memory_limit: str | int | None = None, atmospheres_in_flight: int | None = None,
          restart: bool = False, keep_parts: bool = False, allow_large: bool = False,
          command: str | None = None,
          on_chunk: Callable[[int, int], None] | None = None) -> SweepResult:
    """Diffuse sky radiance (and, from solvers that light surfaces, the surface irradiance)
    for every combination of the config `values` (dotted key -> values, or an axis written
    as text: "0,0.1,0.3", "0.02:0.8:20", "0.01:1:5:log"; `config_overrides`) of `config` (a
    preset name or TOML file), `sun_zeniths_deg` (default 30) or `times` (each as
    `make_observer` takes it: the sun where it stands then, seen from `latitude_deg`,
    `longitude_deg` and `altitude_m`; Earth and Mars presets), `view_zeniths_deg`,
    `relative_azimuths_deg` (0 looks towards the sun) and monochromatic `wavelengths_nm`,
    run on a Dask cluster: a `LocalCluster` of `workers` processes (default: the CPU cores;
    `memory_limit` each), or the scheduler at the address `scheduler`. Each atmosphere's
    solver is built once; at most `atmospheres_in_flight` are held at a time
    (`sweep.run`). Returns a `SweepResult` whose dataset has one dimension per config key
    (`[i]` -> `_i`, `.` -> `_`; attribute `config_key`), then sun_zenith (with `times`: time,
    with the coordinates sun_zenith(time) and sun_azimuth(time)), view_zenith, azimuth,
    wavelength (docs/sweep.md, `sweep.assemble`), written to `output_path` (.nc:
    NetCDF-3, .zarr: a Zarr store) when given. Finished chunks are kept in `OUT.parts/`
    beside it, so an interrupted sweep run again computes only what is missing (`restart`:
    start afresh); the folder is removed when the output is written unless `keep_parts`.
    `on_chunk(done, total)` follows the chunks. `orders` (default: each atmosphere's
    config's), `n_samples`, `seed`, `cache_dir`, `use_cache` as `solver_options`; `command`
    is recorded in the attributes. InputError, before any work, for an unknown key or bad
    value, bad angles or wavelengths, an unknown solver, an output that cannot be written,
    a sweep too large (`render.budget`; `allow_large`), or the `[dask]` extra missing."""
    import_xarray()
    import_distributed()
    plan = _sweep_plan(config, values, sun_zeniths_deg, view_zeniths_deg,
                       relative_azimuths_deg, wavelengths_nm=wavelengths_nm,
                       altitude_m=altitude_m, solver=solver, orders=orders,
                       n_samples=n_samples, seed=seed, cache_dir=cache_dir,
                       use_cache=use_cache)
    if times is not None:
        plan = _sweep_over_times(plan, sun_zeniths_deg, times, latitude_deg, longitude_deg)
    elif latitude_deg is not None or longitude_deg is not None:
        raise InputError("latitude_deg and longitude_deg place the sun of `times`: give times "
                         "too, or leave them out", key="times", value=None)
    if atmospheres_in_flight is not None:
        atmospheres_in_flight = checked_integer("atmospheres_in_flight",
                                                atmospheres_in_flight, 1, 1_000_000)
    output = _checked_sweep_output(output_path)
    rays = plan.n_chunks * len(plan.view_zeniths_deg) * len(plan.relative_azimuths_deg)
    n_wl = len(plan.wavelengths_nm)
    check_cost(f"a sweep of {plan.n_atmospheres} atmospheres x {rays // plan.n_atmospheres} "
               f"geometries at {n_wl} wavelengths", 2.0 * rays * n_wl * 8.0, rays, n_wl,
               solver=solver, n_samples=n_samples, allow_large=allow_large)
    _check_sweep_values(plan)
    base = load_atmosphere(config)
    geometry: dict[str, object] = {"altitude_m": plan.altitude_m,
                                   "sun_zeniths_deg": plan.sun_zeniths_deg}
    if plan.place_deg is not None:  # over times: the sun's zeniths are sun_zenith(time)
        geometry = {"altitude_m": plan.altitude_m, "latitude_deg": plan.place_deg[0],
                    "longitude_deg": plan.place_deg[1], "body": base.planet.body,
                    "azimuth": "relative to the sun's azimuth sun_azimuth(time), 0 towards "
                    "the sun"}
    metadata = output_metadata(
        base, ["radiance"], plan.wavelengths_nm, solver=solver,
        options=SolverOptions(n_samples=n_samples, seed=seed,
                              orders=base.scattering_orders if orders is None else orders),
        geometry={**geometry, "view_zeniths_deg": plan.view_zeniths_deg,
                  "relative_azimuths_deg": plan.relative_azimuths_deg})
    fingerprint = plan.fingerprint()
    metadata.pop("number_format")  # of text rows; a dataset holds the float64 values
    metadata["sweep"] = {"config_keys": ", ".join(key for key, _ in plan.axes),
                         "atmospheres": plan.n_atmospheres, "chunks": plan.n_chunks,
                         "fingerprint": fingerprint, "command": command}
    with contextlib.ExitStack() as stack:
        folder = (parts_folder(output) if output is not None
                  else Path(stack.enter_context(tempfile.TemporaryDirectory())) / "parts")
        store = ChunkStore(folder, fingerprint, {"config": str(plan.config),
                                                 "keys": [key for key, _ in plan.axes],
                                                 "chunks": plan.n_chunks}, restart=restart)
        reused = len(store.finished() & set(range(plan.n_chunks)))
        done = [reused]

        def stored(_: int) -> None:
            done[0] += 1
            if on_chunk is not None:
                on_chunk(done[0], plan.n_chunks)

        if on_chunk is not None:
            on_chunk(reused, plan.n_chunks)
        computed = 0
        if reused < plan.n_chunks:
            with dask_client(scheduler, workers, memory_limit=memory_limit) as client:
                computed = run_sweep(client, plan, store, in_flight=atmospheres_in_flight,
                                     on_chunk=stored)
        dataset = grid_dataset(grid_variables(plan, store), grid_coordinates(plan), metadata,
                               aligned=time_coordinates(plan))
        if output is not None:
            (write_zarr if output.suffix.lower() == ".zarr" else write_netcdf)(dataset, output)
            if not keep_parts:
                store.remove()
    return SweepResult(dataset, output, computed, reused)


def _sweep_plan(config: str | Path, values: Mapping[str, str | Sequence[object]] | None,
                sun_zeniths_deg: Sequence[float] | None, view_zeniths_deg: Sequence[float],
                relative_azimuths_deg: Sequence[float], *, wavelengths_nm: Sequence[float],
                altitude_m: float, solver: str, orders: int | None, n_samples: int, seed: int,
                cache_dir: str | Path | None, use_cache: bool) -> SweepPlan:
    """The plan of `sweep`, its geometry, wavelengths and solver checked."""
    document, path = load_document(config)
    if values is not None and not isinstance(values, Mapping):
        raise InputError(f"values = {values!r} is not allowed: a mapping of dotted config keys "
                         "to values", key="values", value=values,
                         allowed="{key: values} such as {'planet.ground_albedo': '0,0.3'}")
    axes = []
    for key, axis in (values or {}).items():
        if isinstance(axis, str):
            listed = parse_values(axis)
        else:
            listed = list(axis) if isinstance(axis, Sequence | np.ndarray) else [axis]
        if not listed:
            raise InputError(f"{key}: no values to sweep", key=str(key), value=axis)
        axes.append((str(key), tuple(_plain_value(value) for value in listed)))
    if not isinstance(solver, str) or solver not in SOLVERS:
        raise InputError(f"unknown solver {solver!r}; available: {', '.join(SOLVERS)}",
                         key="solver", value=solver, allowed=", ".join(SOLVERS))
    if orders is not None:
        orders = checked_integer("orders", orders, 1, MAX_SCATTERING_ORDERS)
    plan = SweepPlan(
        str(config), document, str(path), tuple(axes),
        tuple(float(v) for v in _angle_list("sun_zeniths_deg", (30.0,) if sun_zeniths_deg is None
                                            else sun_zeniths_deg, ZENITH_DEG)),
        tuple(float(v) for v in _angle_list("view_zeniths_deg", view_zeniths_deg, ZENITH_DEG)),
        tuple(float(v) for v in _angle_list("relative_azimuths_deg", relative_azimuths_deg,
                                            ANGLE_DEG)),
        tuple(float(v) for v in _checked_wavelength_list(wavelengths_nm, True)),
        altitude_m=float(ALTITUDE_M.check("altitude_m", altitude_m)), solver=solver,
        orders=orders, n_samples=checked_integer("n_samples", n_samples, 1, MAX_SAMPLES),
        seed=checked_integer("seed", seed, 0, 2**32 - 1),
        cache_dir=None if cache_dir is None else str(cache_dir), use_cache=bool(use_cache))
    return plan


def _sweep_over_times(plan: SweepPlan, sun_zeniths_deg: Sequence[float] | None,
                      times: Sequence[str | datetime.datetime], latitude_deg: float | None,
                      longitude_deg: float | None) -> SweepPlan:
    """`plan` over `times`: the sun's zenith angle and azimuth at each (`sky_ephemeris` of the
    config's planet, seen from the place at the plan's altitude) in place of its sun zeniths."""
    if sun_zeniths_deg is not None:
        raise InputError("sun_zeniths_deg and times both place the sun: give one",
                         key="times", value=None)
    if latitude_deg is None or longitude_deg is None:
        raise InputError("times need the place too: give latitude_deg and longitude_deg "
                         "(CLI: --lat and --lon, in degrees north and east)", key="latitude_deg",
                         value=(latitude_deg, longitude_deg))
    if isinstance(times, str | datetime.datetime) or not 1 <= len(times) <= MAX_FRAMES:
        raise InputError(f"times: give a list of 1 to {MAX_FRAMES} times", key="times",
                         value=times if isinstance(times, str) else None,
                         allowed=f"1 to {MAX_FRAMES} times")
    atmosphere = load_atmosphere(plan.config)
    suns = [sky_ephemeris(atmosphere, make_observer(time, latitude_deg, longitude_deg,
                                                    plan.altitude_m)) for time in times]
    return replace(
        plan, sun_zeniths_deg=tuple(float(sky.sun_zenith_deg) for sky in suns),
        sun_azimuths_deg=tuple(float(sky.sun.azimuth_deg) for sky in suns),
        times_utc=tuple(sky.observer.time_utc.isoformat() for sky in suns),
        place_deg=(float(latitude_deg), float(longitude_deg)),
        sun_distances_m=tuple(float(sky.sun.distance_m) for sky in suns))


def _check_sweep_values(plan: SweepPlan) -> None:
    """Each value of each axis applied alone (the others as the config has them): the config's
    own checks name a bad key or value before any work."""
    for key, listed in plan.axes:
        for value in listed:
            SweepPlan(plan.config, plan.document, plan.path, ((key, (value,)),), (0.0,),
                      (0.0,), (0.0,), (550.0,)).atmosphere(0)


def _plain_value(value: object) -> object:
    """numpy scalars as Python numbers (the config's parser checks Python types)."""
    return value.item() if isinstance(value, np.generic) else value


def _checked_sweep_output(output_path: str | Path | None) -> Path | None:
    """The sweep's output, named .nc or .zarr, where it and its chunk store can be written."""
    if output_path is None:
        return None
    output = Path(output_path)
    if output.suffix.lower() not in (".nc", ".zarr"):
        raise InputError(f"cannot write a sweep as {str(output)!r}: name it .nc (NetCDF) or "
                         ".zarr (a Zarr store)", key="output", value=str(output),
                         allowed=".nc, .zarr")
    if output.suffix.lower() == ".nc":
        check_writable_file(output)
    elif output.exists() and not output.is_dir():
        raise InputError(f"cannot write {output}: it is a file; a Zarr store is a folder",
                         key="output", value=str(output))
    check_writable_file(parts_folder(output) / "sweep.json")
    return output


def _angle_list(name: str, values: Sequence[float], bounds: Bounds) -> np.ndarray:
    """`values` (a number or a list) as a checked non-empty 1-D array."""
    array = np.atleast_1d(bounds.check_array(name, values))
    if array.ndim != 1 or array.size == 0:
        raise InputError(f"{name} = {values!r} is not allowed: a non-empty list of numbers",
                         key=name, value=values, allowed="a non-empty list of numbers")
    return array


def export_tables(atmosphere: Atmosphere, folder: str | Path, output_format: str = "exr",
                  colour: str = "rgb", *, colour_space: str = "srgb", precision: str = "half",
                  wavelengths_nm: Sequence[float] | None = None,
                  options: SolverOptions | None = None) -> ExportedTables:
    """Write the precomputed tables of `atmosphere` for engines into `folder` (replaced as a
    whole; docs/engines.md, "Exported tables"): transmittance, irradiance, scattering (Bruneton
    2017's 3-D packing) and phase textures as `output_format` "exr", "ktx2" or "npz", with
    `colour` channels "rgb" (linear `colour_space`), "xyz" or "spectral" (one per wavelength
    of `wavelengths_nm`, default 16 bins), in `precision` "half" or "float", plus a JSON
    sidecar with every constant a shader needs and the GLSL and HLSL that read them. The
    tables come from the cache or are computed (`options`, default `solver_options`).
    InputError for an unknown format, colour, colour space or precision, or a folder that
    cannot be written (a file, or a folder holding other files), before any computation."""
    _check_atmosphere(atmosphere)
    settings = ExportSettings(output_format, colour, colour_space, precision, atmosphere.name)
    settings.check()
    check_writable_folder(folder, EXPORT_FILES)
    solver = load_solver(atmosphere, wavelengths_nm, "lut", options)
    return write_exported_tables(solver.tables, solver.profile, folder, settings)


def run_validation(settings: ValidationSettings, cases: Sequence[str] | None = None,
                   on_case: Callable[[CaseResult], None] | None = None, *,
                   scheduler: str | None = None, workers: int | None = None) -> ValidationRun:
    """Run the validation cases `cases` (default: all; `VALIDATION_CASES`) with `settings`,
    write report.md, summary.json and the figures into `settings.output_dir`, and return the
    results (`validate.suite.run_suite`); `on_case` sees each result as it ends. With
    `scheduler` (a Dask scheduler's address) or `workers` (local worker processes) the cases
    run at once on that Dask cluster (`dask_cluster`; the `[dask]` extra); a remote cluster's
    workers must see `settings.output_dir` (a shared file system)."""
    if scheduler is None and workers is None:
        return run_suite(settings, cases, on_case)
    with dask_client(scheduler, workers) as client:
        return run_suite(settings, cases, on_case, client=client)


def compare_techniques(output_dir: str | Path, solvers: Sequence[str] | None = None,
                       atmospheres: Sequence[str] | None = None,
                       sun_zeniths_deg: Sequence[float] | None = None, *, quick: bool = False,
                       paths: int | None = None, cache_dir: str | Path | None = None,
                       use_cache: bool = True, seed: int = 0,
                       log: Callable[[str], None] = print,
                       step: Callable[[int, int, str], None] | None = None
                       ) -> ComparisonResult:
    """Compare `solvers` (default: every one but "montecarlo" and "single") with the Monte Carlo
    reference on `atmospheres` (presets, configs or NAME:CONSTITUENT*FACTOR variants; default
    earth, earth:aerosol*4, mars-physical) at `sun_zeniths_deg` (default 0, 30, 60, 80, 94) and
    write report.md, results.json and PNG figures into `output_dir`
    (`validate.technique_comparison`). `quick`: a few directions, 2 bands, few paths; `paths`:
    Monte Carlo paths per direction and band by day. The tables and the Monte Carlo means are
    cached in `cache_dir` (default: `default_cache_directory()`) unless `use_cache` is False.
    InputError, before any work, for an unknown solver or atmosphere, bad angles or paths, or
    an output folder that cannot be written."""
    from skyscatter.validate.technique_comparison import comparison_plan, run_comparison
    seed = checked_integer("seed", seed, 0, 2**32 - 1)
    if paths is not None:
        paths = checked_integer("paths", paths, 100, 1_000_000)
    plan = comparison_plan(quick, solvers, atmospheres, sun_zeniths_deg, paths=paths)
    for spec in plan.atmospheres:
        load_variant(spec)  # a misspelt atmosphere fails now, not after the first one's work
    check_writable_file(Path(output_dir) / "report.md")
    return run_comparison(plan, output_dir, cache=TableCache(cache_dir) if use_cache else None,
                          seed=seed, log=log, step=step)


def viewer_server(config: str | Path | None = None, host: str = "127.0.0.1", port: int = 0, *,
                  cache_dir: str | Path | None = None, use_cache: bool = True,
                  log: Callable[[str], None] | None = None) -> ViewerServer:
    """The real-time viewer's web server (`viewer.server`), not yet serving: `config` (a
    preset name or TOML file) is the atmosphere shown first, besides the presets; the full
    tables come from and go to the table cache (`cache_dir`, default
    `default_cache_directory()`) unless `use_cache` is False. `log` gets the requests and
    where tables came from. The server's `url` carries its per-launch token, which every API
    request needs (`viewer.server`: who may ask). Serve it with `serve_viewer(server)`."""
    cache = TableCache(cache_dir) if use_cache else None
    service = TableService(config, cache, log)

    def sky_at(atmosphere: Atmosphere, time: str, latitude_deg: float,
               longitude_deg: float) -> dict:
        return sky_message(atmosphere.planet.body,
                           make_observer(time, latitude_deg, longitude_deg),
                           atmosphere.planet.star)

    return make_server(service, sky_at, host, port, log)


def serve_viewer(server: ViewerServer, open_browser: bool = True) -> None:
    """Serve the viewer of `viewer_server` until Ctrl-C, opening its page in the default
    browser first if `open_browser`; closes the server (`viewer.server.serve_forever`)."""
    viewer_server_module.serve_forever(server, open_browser)


def is_loopback(host: str) -> bool:
    """True for "localhost" and the loopback addresses (127.0.0.0/8, ::1)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


FIT_SOLVERS = (*FAST_SOLVERS, "lut")  # the forward models of a fit's first stage
FIT_REFINE = ("lut",)  # the exact solver a fit may refine with
FIT_CHECKS = ("lut", "montecarlo")  # the exact solvers that check a fit's answer


def fit(config: str | Path, measurements: str | Path | Sequence[dict],
        free: Sequence[str | FreeParameter], *, solver: str = "hillaire",
        model: str | Path | None = None, refine: str | None = None,
        checks: Sequence[str] = (), relative_uncertainty: float | None = None,
        model_error: float | None = None, model_error_correlation: float = 0.0,
        relative_weights: bool = False, altitude_m: float = 0.0, samples: int = 64,
        check_samples: int = 4000) -> Retrieval:
    """Estimate the config values `free` (`KEY=LOW:HIGH[:START]` or `FreeParameter`) of the
    preset or config file `config` from `measurements` (a CSV/JSON file or rows as dicts,
    docs/fit.md), with uncertainties (`fit.retrieval`).

    The forward model is `solver` (one of `FIT_SOLVERS`, default "hillaire") or, with `model`,
    interpolation in a sweep file (NetCDF/Zarr of `skyscatter sweep`); `refine` ("lut") fits
    again with the tables from that answer; each of `checks` ("lut", "montecarlo" with
    `check_samples` paths per value) is evaluated at the answer. Rows without an uncertainty
    take `relative_uncertainty` x value; `model_error` replaces the forward model's stated
    error (a fraction for radiance, absolute for chromaticity), `model_error_correlation` (0-1)
    the share of its variance common to the values of one kind; `relative_weights` scales the
    covariance by the reduced chi-square. `samples`: ray-marching samples per view ray of the
    solvers (as `solver_options`). InputError, before any work, for a bad key, bounds,
    file, row or option."""
    document, path = load_document(config)
    parameters = checked_free(free, document)
    if isinstance(measurements, str | Path):
        rows = read_measurements(measurements, relative_uncertainty)
    else:
        rows = measurements_from_rows(list(measurements), relative_uncertainty)
    if solver not in FIT_SOLVERS:
        raise InputError(f"solver = {solver!r} is not a fit's forward model: one of "
                         f"{', '.join(FIT_SOLVERS)}", key="solver", value=solver,
                         allowed=", ".join(FIT_SOLVERS))
    if refine is not None and refine not in FIT_REFINE:
        raise InputError(f"refine = {refine!r}: only {', '.join(FIT_REFINE)}", key="refine",
                         value=refine, allowed=", ".join(FIT_REFINE))
    for name in checks:
        if name not in FIT_CHECKS:
            raise InputError(f"check = {name!r}: one of {', '.join(FIT_CHECKS)}", key="check",
                             value=name, allowed=", ".join(FIT_CHECKS))
    if model_error is not None:
        checked_number("model_error", model_error, 0.0, 10.0)
    checked_number("model_error_correlation", model_error_correlation, 0.0, 1.0)
    ALTITUDE_M.check("altitude_m", altitude_m)
    paths = checked_integer("check_samples", check_samples, 1, MAX_SAMPLES)
    common = {"altitude_m": altitude_m,
              "samples": checked_integer("samples", samples, 1, MAX_SAMPLES)}
    if model is not None:
        forward = SweepModel(_read_sweep(model), parameters,
                             model_error_override=model_error, label=str(model))
    else:
        forward = SolverModel(document, path, solver, model_error_override=model_error,
                              **common)
    exact = SolverModel(document, path, refine, **common) if refine else None
    check_models = [SolverModel(document, path, name, **(common | {"samples": paths})
                                if name == "montecarlo" else common) for name in checks]
    return retrieve(rows, parameters, forward, refine=exact, checks=check_models,
                    relative_weights=relative_weights,
                    model_error_correlation=model_error_correlation)



def _read_sweep(path: str | Path):
    """The dataset of a sweep file (NetCDF, or a Zarr folder), loaded into memory."""
    xarray = import_xarray()
    source = Path(path)
    if not source.exists():
        raise InputError(f"sweep {source}: no such file", key="model", value=str(source))
    try:
        if source.is_dir():
            return xarray.open_zarr(source).load()
        with xarray.open_dataset(source) as dataset:
            return dataset.load()
    except Exception as error:  # any reader's complaint about a bad file
        raise InputError(f"sweep {source}: cannot read it ({type(error).__name__}: "
                         f"{error}); give a NetCDF file or Zarr folder of `skyscatter sweep`",
                         key="model", value=str(source)) from None


def image_measurements(exr_path: str | Path, camera: Camera, sun_zenith_deg: float,
                       sun_azimuth_deg: float = 180.0, *, pixels: int = 200,
                       seed: int = 0) -> list[dict[str, float]]:
    """Luminance rows [cd m^-2] of `pixels` sky pixels drawn (`seed`) from a linear EXR of
    `render`/`save_image` ("rgb" or "luminance" content) taken by `camera` with the sun at
    `sun_zenith_deg`, `sun_azimuth_deg` (from north towards east) [deg], for `fit`
    (`fit.image_samples`). InputError for a missing or unreadable EXR, one without
    luminance, a size that is not the camera's, or fewer sky pixels than `pixels`."""
    _check_camera(camera)
    ZENITH_DEG.check("sun_zenith_deg", sun_zenith_deg)
    ANGLE_DEG.check("sun_azimuth_deg", sun_azimuth_deg)
    return image_rows(exr_path, camera, sun_zenith_deg, sun_azimuth_deg,
                      pixels=checked_integer("pixels", pixels, 1, 1_000_000),
                      seed=checked_integer("seed", seed, 0, 2**32 - 1))


def measurement_rows(path: str | Path) -> list[dict]:
    """The rows of a measurement file (CSV or JSON, docs/fit.md) as dicts, to combine with
    `image_measurements` before `fit`; InputError for a missing or garbled file."""
    return read_rows(path)
