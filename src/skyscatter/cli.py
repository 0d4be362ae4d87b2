"""Command line: `skyscatter render | timelapse | radiance | sweep | precompute | validate |
compare | presets`
(and `completion`, from `cli_completion`).
Thin: parse,
call the library, print.

User errors (`SkyscatterError`) print one line and exit with code 2; anything else is our bug
and exits with 1 (the traceback only with --debug). `validate` exits with 3 when a check fails
its limit. Progress bars appear only on a terminal.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import os
import re
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, redirect_stderr
from pathlib import Path
from typing import NoReturn

from skyscatter import __version__, checks
from skyscatter.api_constants import (  # no solver
    AU_M,
    COLOUR_RANGE_NM,
    CUBE_LAYOUTS,
    DEFAULT_WAVELENGTH_BINS,
    VALIDATION_CASES,
    solver_descriptions,
)
from skyscatter.checks import Bounds
from skyscatter.errors import InputError
from skyscatter.output_files import atomic_write, check_writable_file, staged_outputs
from skyscatter.row_output import (
    METADATA_PLACES,
    metadata_json,
    rows_csv,
    rows_json,
    sidecar_path,
    tidy,
)

__all__ = ["main"]

CAMERAS = ("fisheye", "panorama", "perspective", "orbit", "cubemap", "octahedral", "sphere",
           "paraboloid")
WHOLE_SPHERE = ("cubemap", "octahedral", "panorama", "sphere", "paraboloid")


def _checked(bounds: Bounds, value: float, text: str) -> float:
    """`value` (read from `text`) within `bounds` (`checks`), else the argparse error."""
    try:
        return bounds.check("value", value)
    except InputError:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: {bounds.allowed}") from None


def _number(bounds: Bounds) -> Callable[[str], float]:
    """An argparse type: a number within `bounds`, the same check the API makes."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        return _checked(bounds, value, text)
    return parse


def _whole(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: a whole number from `low` to `high` (`checks.checked_integer`)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        try:
            return checks.checked_integer("value", value, low, high)
        except InputError as error:
            raise argparse.ArgumentTypeError(f"{value} is not allowed: {error.allowed}") from None
    return parse


def _float_list(text: str, bounds: Bounds = checks.ANY_NUMBER) -> list[float]:
    """'0,30,60' -> [0.0, 30.0, 60.0], each within `bounds` (argparse type: `_number_list`)."""
    parts = [part for part in text.split(",") if part.strip()]
    try:
        values = [float(part) for part in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a comma-separated list of numbers (e.g. 0,30,60)") from None
    if not values:
        raise argparse.ArgumentTypeError("the list is empty; give numbers like 0,30,60")
    return [_checked(bounds, value, part.strip()) for value, part in zip(values, parts,
                                                                           strict=True)]


def _number_list(bounds: Bounds) -> Callable[[str], list[float]]:
    """An argparse type: a comma-separated list of numbers within `bounds`."""
    def parse(text: str) -> list[float]:
        return _float_list(text, bounds)
    return parse


def _wavelength_list(monochromatic: bool) -> Callable[[str], list[float]]:
    """An argparse type: wavelengths [nm] within the shipped data's range
    (`spectrum.grid.checked_data_wavelengths`)."""
    def parse(text: str) -> list[float]:
        from skyscatter import api
        low, high = api.MONOCHROMATIC_RANGE_NM if monochromatic else api.COLOUR_RANGE_NM
        data = ("the solar spectrum and the gases' refractive indices" if monochromatic
                else "the CIE colour-matching functions")
        try:
            return _float_list(text, Bounds(low, high))
        except argparse.ArgumentTypeError as error:
            if "is not allowed" not in str(error):
                raise
            raise argparse.ArgumentTypeError(f"{error} nm, the range of {data}") from None
    return parse


def _name_list(text: str) -> list[str]:
    """'a,b' -> ['a', 'b'] (argparse type)."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    if not names:
        raise argparse.ArgumentTypeError("the list is empty; give names like disort,cie-sky")
    return names


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{value} must be > 0")
    return value


def _size(text: str) -> int:
    """Image height in pixels, 1 to `render.camera.MAX_SIDE_PIXELS` (argparse type)."""
    from skyscatter import api
    return _whole(1, api.MAX_SIDE_PIXELS)(text)


def _orders(text: str) -> int:
    """Scattering orders, 1 to the config's `MAX_SCATTERING_ORDERS` (argparse type)."""
    from skyscatter import api
    return _whole(1, api.MAX_SCATTERING_ORDERS)(text)


def _samples(text: str) -> int:
    """Samples per ray, 1 to `render.budget.MAX_SAMPLES` (argparse type)."""
    from skyscatter import api
    return _whole(1, api.MAX_SAMPLES)(text)


def _frame_count(text: str) -> int:
    """Frames of a time-lapse, 1 to `render.budget.MAX_FRAMES` (argparse type)."""
    from skyscatter import api
    return _whole(1, api.MAX_FRAMES)(text)


def _exposure(text: str) -> float | None:
    if text == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is neither 'auto' nor an EV100 number") from None
    return _checked(checks.EV, value, text)


_DURATION_UNITS = {"s": 1.0, "sec": 1.0, "min": 60.0, "m": 60.0, "h": 3600.0, "d": 86400.0}
_DURATION_S = Bounds(0.0, 1e12, low_open=True)  # s; up to 31 700 years


def _duration_s(text: str) -> float:
    """'10min' -> 600.0, '30s', '1.5h', '1d' (argparse type) [s]."""
    stripped = text.strip().lower()
    for unit in sorted(_DURATION_UNITS, key=len, reverse=True):
        if stripped.endswith(unit):
            try:
                value = float(stripped[: -len(unit)]) * _DURATION_UNITS[unit]
            except ValueError:
                break
            return _checked(_DURATION_S, value, text)
    raise argparse.ArgumentTypeError(
        f"{text!r} is not a duration; write a number with a unit: 30s, 10min, 1.5h, 1d")


# 471: the 1 nm bins over COLOUR_RANGE_NM (360-830 nm), the resolution of the CIE tables
MAX_BINS = round(COLOUR_RANGE_NM[1] - COLOUR_RANGE_NM[0]) + 1


def _wavelengths(text: str) -> list[float]:
    """'16' -> a 16-bin grid over 360-830 nm; '440,550,680' -> those wavelengths."""
    if "," not in text:
        count = _positive_int(text)
        if count > MAX_BINS:
            raise argparse.ArgumentTypeError(
                f"{count} bins is more than the {MAX_BINS} 1-nm bins of "
                f"{COLOUR_RANGE_NM[0]:g}-{COLOUR_RANGE_NM[1]:g} nm; for one "
                "wavelength write it as a list, e.g. 550,")
        from skyscatter import api
        return list(api.wavelength_grid(count))
    return _wavelength_list(monochromatic=False)(text)


def _look_at(text: str) -> tuple[float, float, float]:
    """'LAT,LON' or 'LAT,LON,ALT_KM' -> (lat, lon, altitude_km)."""
    values = _float_list(text)
    if len(values) not in (2, 3):
        raise argparse.ArgumentTypeError(
            f"{text!r} should be LAT,LON or LAT,LON,ALT_KM (degrees, degrees, km)")
    altitude_km = values[2] if len(values) == 3 else 0.0
    return (_checked(checks.LATITUDE_DEG, values[0], f"{values[0]:g}"),
            _checked(checks.ANGLE_DEG, values[1], f"{values[1]:g}"),
            _checked(_ALTITUDE_KM, altitude_km, f"{altitude_km:g}"))


_ALTITUDE_KM = Bounds(checks.ELEVATION_M.low / 1e3, checks.ELEVATION_M.high / 1e3)
_DISTANCE_KM = Bounds(0.0, checks.ALTITUDE_M.high / 1e3, low_open=True)
_TERRAIN_M = Bounds(0.0, 1e5, low_open=True)  # m; heightmap spacing and height (100 km)
_CLOUD_TIME_S = Bounds(-1e12, 1e12)  # s; years 1-9999 from J2000, as the dated renders
_MAGNITUDE = Bounds(-30.0, 30.0)  # V magnitudes: the sun is -26.7, Hipparcos ends near 14
_MINUTES = Bounds(0.0, 1e7)  # simulated minutes (19 years)
_POSITIVE = Bounds(0.0, None, low_open=True)
_ALLOW_LARGE_HELP = ("run even when the estimated memory exceeds this computer's or the "
                     "computing time exceeds an hour (refused by default, with the estimate)")


def _add_atmosphere_argument(command: argparse.ArgumentParser) -> None:
    """The atmosphere a command works on, a preset name or a TOML file."""
    command.add_argument("atmosphere", metavar="PRESET_OR_CONFIG",
                         help="a preset name (see `skyscatter presets`) or a TOML file")


def _add_solver_arguments(command: argparse.ArgumentParser, samples_default: int) -> None:
    """--solver, --orders, --samples and the table cache options."""
    command.add_argument("--solver", default="lut", metavar="NAME")  # help: _Parser
    command.add_argument("--orders", type=_orders, default=None,
                         help="scattering orders of the tables (default: the config's "
                         "[tables] orders: 8 for the earth preset)")
    command.add_argument("--samples", type=_samples, default=samples_default,
                         help="single, hillaire, schuler: ray-marching samples per view ray; "
                         "montecarlo: paths per view ray and wavelength (default "
                         f"{samples_default})")
    command.add_argument("--allow-large", action="store_true", help=_ALLOW_LARGE_HELP)
    _add_cache_arguments(command)


def _add_cache_arguments(command: argparse.ArgumentParser) -> None:
    command.add_argument("--cache-dir", type=Path, default=None, metavar="DIR",
                         help="where tables are cached (default: $SKYSCATTER_CACHE_DIR, else "
                         "$XDG_CACHE_HOME/skyscatter or ~/.cache/skyscatter)")
    command.add_argument("--no-cache", action="store_true",
                         help="compute the tables in memory; neither read nor write the cache")


def _add_place_arguments(command: argparse.ArgumentParser, required: bool = False) -> None:
    """--lat/--lon/--elevation-m: the observer's place for --time (and, for --camera orbit, the
    point below the camera)."""
    command.add_argument("--lat", type=_number(checks.LATITUDE_DEG), default=None,
                         required=required, metavar="DEG",
                         help="observer latitude in degrees, north positive (with --time; "
                         "orbit camera: the latitude below it, default 0)")
    command.add_argument("--lon", type=_number(checks.ANGLE_DEG), default=None,
                         required=required, metavar="DEG",
                         help="observer longitude in degrees, east positive (with --time; "
                         "orbit camera: the longitude below it, default 0)")
    command.add_argument("--elevation-m", "--altitude", dest="altitude",
                         type=_number(checks.ELEVATION_M),
                         default=0.0, metavar="M",
                         help="observer height above the ground (sea level) in metres "
                         "(default 0)")


_CAMERA_HELP = {
    "fisheye": "all-sky, zenith at centre, north up, east left",
    "panorama": "equirectangular 2:1",
    "perspective": "pinhole",
    "orbit": "the planet from space, looking at its centre from --distance-km above --lat/--lon, "
             "north up",
    "cubemap": "the whole sphere on six --size faces in OpenGL's cube map convention (+X east, "
               "+Y up, +Z south), laid out by --cube-layout",
    "octahedral": "the whole sphere on one --size square as light probes store it: the zenith "
                  "at the centre, the horizon on the inner diamond, the nadir at the corners",
    "sphere": "the whole sphere as OpenGL's sphere map (a mirror ball seen from above) on one "
              "--size square: the zenith at the centre, the nadir on the rim",
    "paraboloid": "the whole sphere on two --size paraboloid maps side by side (Heidrich & "
                  "Seidel 1998): upper hemisphere left, lower right, the horizon on the rims",
}


def _add_camera_arguments(command: argparse.ArgumentParser, cameras: Sequence[str],
                          size_default: int) -> None:
    """--camera (one of `cameras`), --size, --aspect, --fov, --heading, --pitch."""
    command.add_argument("--camera", choices=cameras, default="fisheye",
                         help="; ".join(f"{name}: {_CAMERA_HELP[name]}" for name in cameras)
                         + " (default fisheye)")
    command.add_argument("--size", type=_size, default=size_default, metavar="PIXELS",
                         help="image height in pixels (panorama width = 2 x size; "
                         "perspective width from --aspect; cubemap: a face's side) "
                         f"(default {size_default})")
    command.add_argument("--aspect", type=_number(checks.ASPECT), default=16 / 9,
                         help="perspective width / height (default 16/9)")
    orbit = "; orbit: the whole planet" if "orbit" in cameras else ""
    command.add_argument("--fov", type=_number(checks.PERSPECTIVE_FOV_DEG), default=None,
                         metavar="DEG", help="vertical field of view in degrees (default 60 "
                         f"for perspective{orbit})")
    command.add_argument("--heading", type=_number(checks.ANGLE_DEG), default=180.0,
                         metavar="DEG",
                         help="view azimuth from north towards east for perspective and "
                         "panorama centre, degrees (default 180: south)")
    command.add_argument("--pitch", type=_number(checks.ELEVATION_ANGLE_DEG), default=10.0,
                         metavar="DEG",
                         help="perspective view elevation in degrees (default 10)")
    if "cubemap" in cameras:
        command.add_argument("--cube-layout", choices=tuple(CUBE_LAYOUTS), default="cross",
                             help="cubemap faces: cross (4 x 3: +Y above +Z; -X +Z +X -Z; -Y "
                             "below) or strip (6 x 1: +X -X +Y -Y +Z -Z) (default cross)")


def _add_wavelength_argument(command: argparse.ArgumentParser) -> None:
    """--wavelengths of an image: N bins over the visible, or a list."""
    command.add_argument("--wavelengths", type=_wavelengths, default=None, metavar="N|LIST",
                         help="N bins over 360-830 nm, or a comma-separated list in nm "
                         f"(default {DEFAULT_WAVELENGTH_BINS} bins)")


def _add_image_arguments(command: argparse.ArgumentParser) -> None:
    """--exposure-compensation, --tonemap, --colour-space (`api.ImageOptions`)."""
    command.add_argument("--exposure-compensation", type=_number(checks.EV), default=1.0,
                         metavar="EV",
                         help="brightens the metered exposure by this many stops (default +1: "
                         "a clear sky metered to middle grey looks a stop too dark)")
    command.add_argument("--tonemap", default="aces",
                         help="aces (filmic, default), exponential (Costa/Bruneton), "
                         "reinhard or clamp")
    command.add_argument("--colour-space", default="srgb",
                         help="srgb (default), rec709, display-p3, rec2020, acescg or "
                         "aces2065-1")


def _add_sky_object_arguments(command: argparse.ArgumentParser) -> None:
    """What is drawn besides the atmosphere in skies at a date (--time)."""
    command.add_argument("--no-stars", action="store_true", help="leave out the stars")
    command.add_argument("--no-moon", action="store_true",
                         help="leave out the moon and moonlight")
    command.add_argument("--no-airglow", action="store_true",
                         help="leave out the night glow of the upper atmosphere (Earth)")
    command.add_argument("--milky-way", action="store_true",
                         help="add the integrated light of the stars fainter than the "
                         "catalogue (the Milky Way)")
    command.add_argument("--magnitude-limit", type=_number(_MAGNITUDE), default=None,
                         metavar="MAG",
                         help="draw the stars brighter than this V magnitude (default: the "
                         "whole Hipparcos catalogue, about 118 000 stars)")
    command.add_argument("--twinkle", type=_whole(0, 2**64 - 1), default=None, metavar="SEED",
                         help="stars scintillate (random, seeded; in a time-lapse one draw per "
                         "frame)")


class _Parser(argparse.ArgumentParser):
    """An argument parser whose --solver help lists the registered solvers
    (`api_constants.solver_descriptions`), read only when a help text is shown, and whose
    errors suggest the nearest command, choice or option for a mistyped one."""

    def error(self, message: str) -> NoReturn:
        super().error(message + _did_you_mean(message, self))

    def format_help(self) -> str:
        for action in self._actions:
            if action.dest == "solver" and action.help is None:
                action.help = "; ".join(
                    f"{name}{' (default)' if name == action.default else ''}: {description}"
                    for name, description in solver_descriptions().items())
        return super().format_help()


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """`parser.parse_args(argv)`, except that an optional positional (`fit`'s MEASUREMENTS)
    may also come after the options: argparse fills it, empty, together with the positional
    before it, and then refuses the file at the end as unrecognized."""
    args, extra = parser.parse_known_args(argv)
    if len(extra) == 1 and not extra[0].startswith("-"):
        for action in _command_actions(parser, args.command):
            if (not action.option_strings and action.nargs == "?"
                    and action.default is None and getattr(args, action.dest) is None):
                setattr(args, action.dest, action.type(extra[0]) if action.type else extra[0])
                return args
    if extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def _command_actions(parser: argparse.ArgumentParser, command: str) -> list[argparse.Action]:
    """The arguments of `parser`'s command `command`."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and command in action.choices:
            return list(action.choices[command]._actions)
    return []


def _did_you_mean(message: str, parser: argparse.ArgumentParser) -> str:
    """"; did you mean ...?" for argparse's `message` about an invalid choice or unrecognized
    options, from the choices it lists or the options of `parser` and of the command run
    (`parser.argv`, set by `main`; all commands' without it), and which commands have an
    option the command run lacks; or ""."""
    invalid = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
    if invalid:
        choices = [choice.strip("'") for choice in invalid.group(2).split(", ")]
        close = difflib.get_close_matches(invalid.group(1), choices, n=1)
        return f"; did you mean {close[0]!r}?" if close else ""
    if "unrecognized arguments:" not in message:
        return ""
    own = {option for action in parser._actions for option in action.option_strings}
    commands = {name: {option for sub in command._actions for option in sub.option_strings}
                for action in parser._actions if isinstance(action, argparse._SubParsersAction)
                for name, command in action.choices.items()}
    used = next((token for token in getattr(parser, "argv", ()) if token in commands), None)
    options = own | (commands[used] if used else set().union(*commands.values()))
    hints, elsewhere = [], []
    for token in message.split("unrecognized arguments:", 1)[1].split():
        if not token.startswith("--"):
            continue
        name = token.split("=", 1)[0]
        others = sorted(command for command, theirs in commands.items() if name in theirs)
        close = difflib.get_close_matches(name, sorted(options), n=1)
        if used and others and name not in options:
            elsewhere.append(f"{name} is an option of {', '.join(others)}, not of {used} "
                             f"(`skyscatter {used} --help` lists its options)")
        elif close:
            hints.append(f"{close[0]} for {token}")
    text = f"; did you mean {', '.join(hints)}?" if hints else ""
    return text + "".join(f"; {line}" for line in elsewhere)


def _add_sun_zeniths_argument(command: argparse.ArgumentParser) -> None:
    """--sun-zenith (a list) or --time: where the sun stands for a table of numbers."""
    sun = command.add_mutually_exclusive_group(required=True)
    sun.add_argument("--sun-zenith", type=_number_list(checks.ZENITH_DEG), metavar="DEG,...",
                     help="sun zenith angles in degrees")
    sun.add_argument("--time", default=None, metavar="ISO8601",
                     help="date and time with a time zone: the sun's zenith angle there and "
                     "then for --lat/--lon, its light scaled to its distance that day (Earth "
                     "and Mars presets)")


def _add_rows_arguments(command: argparse.ArgumentParser) -> None:
    """--wavelengths, the place, the solver and --format of a command printing rows."""
    command.add_argument("--wavelengths", type=_wavelength_list(monochromatic=True),
                         default=[440.0, 550.0, 680.0],
                         metavar="NM,...", help="wavelengths in nm (default 440,550,680)")
    _add_place_arguments(command)
    _add_solver_arguments(command, 512)
    command.add_argument("--format", choices=("csv", "json"), default=None,
                         help="output format (default: -o's suffix .csv or .json, json for "
                         "--metadata envelope, else csv)")
    command.add_argument("-o", "--output", type=Path, default=None, metavar="FILE",
                         help="write the rows to FILE (.csv, .json, or .nc: a NetCDF dataset "
                         "with units and metadata, needs the [science] extra) instead of "
                         "standard output")
    command.add_argument("--metadata", choices=METADATA_PLACES, default=None,
                         help="also give the run's metadata (units of every column, "
                         "atmosphere and its SHA-256, solver and its options, wavelengths, "
                         "version, time): 'envelope' (JSON) wraps the rows as {\"metadata\": ..., "
                         "\"rows\": [...]}, 'comments' (CSV) puts '# key: value' lines before "
                         "the header, 'sidecar' writes FILE.meta.json beside -o FILE. Without "
                         "it the output is the plain rows")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="skyscatter", description="Physically based skies of Earth, Mars and other "
        "planets: spectral radiance and images from atmosphere descriptions (TOML).")
    parser.add_argument("--version", action="version", version=f"skyscatter {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    presets = commands.add_parser("presets", help="list the shipped atmosphere presets",
                                  description="List the shipped presets with a one-line "
                                  "description each.")
    presets.add_argument("--verbose", action="store_true",
                         help="also print the numbers derived for each preset's [gas] table: "
                         "molar mass, scale height, surface density, column and Rayleigh "
                         "optical depth at 440/550/680 nm")
    presets.set_defaults(run=_presets)

    render = commands.add_parser(
        "render", help="render a sky image (PNG and/or EXR)",
        description="Render the sky seen from the ground or the air to a tone-mapped PNG and "
        "optionally a linear EXR in physical units. Example: skyscatter render earth "
        "--sun-elevation 5 --camera panorama -o sunset.png --exr sunset.exr")
    _add_atmosphere_argument(render)
    sun = render.add_mutually_exclusive_group()
    sun.add_argument("--sun-zenith", type=_number(checks.ZENITH_DEG), metavar="DEG",
                     help="sun zenith angle in degrees (0 = overhead)")
    sun.add_argument("--sun-elevation", type=_number(checks.ELEVATION_ANGLE_DEG), metavar="DEG",
                     help="sun elevation above the horizon in degrees (default 30)")
    sun.add_argument("--time", default=None, metavar="ISO8601",
                     help="date and time with a time zone, e.g. 2024-06-21T21:30+02:00 or "
                     "2024-06-21T21:30[Europe/Berlin], or a Mars Sol Date, e.g. 'MSD 51000.5': "
                     "the sun, moon and stars for --lat/--lon (Earth and Mars presets)")
    render.add_argument("--sun-azimuth", type=_number(checks.ANGLE_DEG), default=180.0,
                        metavar="DEG",
                        help="sun azimuth from north towards east in degrees (default 180)")
    _add_camera_arguments(render, CAMERAS, 512)
    render.add_argument("--distance-km", type=_number(_DISTANCE_KM), default=None, metavar="KM",
                        help="orbit camera: height above the ground in km (default: the "
                        "planet's radius)")
    _add_place_arguments(render)
    render.add_argument("--look-at", type=_look_at, default=None, metavar="LAT,LON[,ALT_KM]",
                        help="orbit camera: aim at this point instead of the planet's centre "
                        "(the local vertical stays up, so the horizon is level)")
    _add_wavelength_argument(render)
    _add_solver_arguments(render, 64)
    render.add_argument("--albedo-map", type=Path, default=None, metavar="IMAGE",
                        help="equirectangular ground albedo (PNG/JPEG sRGB, EXR or .npy linear; "
                        "column 0 at longitude -180, row 0 at the north pole), e.g. for "
                        "--camera orbit")
    render.add_argument("--terrain", default=None, metavar="IMAGE|demo",
                        help="heightmap around the observer (grayscale PNG/EXR/.npy, row 0 = "
                        "north, centred on the observer), or 'demo' for procedural mountains "
                        "10-60 km to the south")
    render.add_argument("--terrain-spacing", type=_number(_TERRAIN_M), default=250.0,
                        metavar="M",
                        help="distance between heightmap samples in metres (default 250)")
    render.add_argument("--terrain-height", type=_number(_TERRAIN_M), default=4500.0,
                        metavar="M",
                        help="height of full white in the heightmap in metres; for 'demo', "
                        "the highest peak (default 4500)")
    _add_cloud_argument(render)
    render.add_argument("--cloud-time", type=_number(_CLOUD_TIME_S), default=0.0, metavar="S",
                        help="seconds the wind has moved the clouds from their initial state "
                        "(default 0; with --time the clouds' time is the date's)")
    _add_sky_object_arguments(render)
    render.add_argument("--exposure", type=_exposure, default=None, metavar="EV100|auto",
                        help="exposure value EV100, or auto (default auto)")
    _add_image_arguments(render)
    render.add_argument("--white-balance", choices=("none", "star"), default="none",
                        help="none, or adapt the star's white (its top-of-atmosphere "
                        "spectrum) to D65 (default none)")
    render.add_argument("-o", "--output", type=Path, default=Path("sky.png"),
                        help="display image: .png, .jpg or .jpeg, .tif or .tiff, .webp "
                        "(lossless), or - for a PNG on standard output (default sky.png; "
                        "missing folders are made)")
    render.add_argument("--exr", type=Path, default=None,
                        help="also write a linear image: OpenEXR (.exr) or Radiance RGBE (.hdr, "
                        "RGB only); it and the display image replace old files together, or "
                        "neither does")
    render.add_argument("--light", type=Path, default=None, metavar="FILE",
                        help="also write the sun as a directional light and the rest of the "
                        "sky's diffuse irradiance as spherical harmonics, in the EXR's units "
                        "(JSON; --camera cubemap, octahedral, panorama, sphere or paraboloid: "
                        "docs/engines.md)")
    render.add_argument("--mips", type=int, default=None, metavar="LEVELS",
                        help="with --camera cubemap and --exr: also write the specular mip "
                        "chain, GGX-prefiltered (roughness k/(LEVELS-1) at level k, faces "
                        "halved at each), as FILE_mip1.exr ... beside the --exr FILE "
                        "(docs/engines.md)")
    _add_ground_argument(render)
    render.add_argument("--no-sun-disk", action="store_true",
                        help="leave the sun's disk out of the image (with --light the sun is "
                        "then only the directional light)")
    render.add_argument("--exr-content",
                        choices=("rgb", "luminance", "spectral", "spectral-fichet2021"),
                        default="rgb", help="what the EXR holds (default rgb); "
                        "spectral-fichet2021: the spectra as channels S0.550,000000nm ... that "
                        "spectral renderers read (Fichet et al. 2021, JCGT 10(3)), with R, G, B")
    render.set_defaults(run=_render)

    timelapse = commands.add_parser(
        "timelapse", help="render a day-night sequence to MP4 or GIF plus the frames",
        description="Render the sky over a time range at one place, frame by frame, reusing "
        "the precomputed tables; the exposure adapts smoothly from day to night. Writes the "
        "video (.mp4 or .gif) and every frame as PNG. Example: skyscatter timelapse earth "
        "--start 2024-06-21T20:00+02:00 --end 2024-06-22T00:00+02:00 --step 10min --lat 52.52 "
        "--lon 13.40 -o berlin.mp4")
    timelapse.add_argument("atmosphere", metavar="PRESET_OR_CONFIG",
                           help="an Earth or Mars preset, or a TOML file with [planet] body")
    _add_time_range_arguments(timelapse, "frame")
    _add_place_arguments(timelapse, required=True)
    _add_camera_arguments(timelapse, CAMERAS[:3], 384)
    _add_wavelength_argument(timelapse)
    _add_solver_arguments(timelapse, 64)
    _add_cloud_argument(timelapse)
    _add_sky_object_arguments(timelapse)
    timelapse.add_argument("--fps", type=_number(_POSITIVE), default=12.0,
                           help="video frames per second (default 12)")
    timelapse.add_argument("--adaptation-minutes", type=_number(_MINUTES), default=10.0,
                           metavar="MIN",
                           help="time constant of the exposure's adaptation, in simulated "
                           "minutes (default 10; 0 meters every frame on its own)")
    _add_image_arguments(timelapse)
    timelapse.add_argument("-o", "--output", type=Path, default=Path("timelapse.mp4"),
                           help="video path, .mp4 (needs `pip install skyscatter[video]`) or "
                           ".gif (default timelapse.mp4)")
    timelapse.add_argument("--frames-dir", type=Path, default=None, metavar="DIR",
                           help="where the PNG frames go (default: beside the video, "
                           "<name>_frames/); the folder holds only frames and is replaced as "
                           "a whole when the run completes")
    _add_cluster_arguments(timelapse, "(default: this process renders the frames)",
                           "to render the frames on (default: none, this process renders "
                           "them)")
    timelapse.set_defaults(run=_timelapse)
    _add_envmap_command(commands)

    radiance = commands.add_parser(
        "radiance", help="print spectral sky radiance as CSV or JSON",
        description="Print diffuse spectral sky radiance [W m^-2 sr^-1 nm^-1] (the sun disk "
        "itself not included) for every combination of the lists. View zenith 0 looks straight "
        "up; relative azimuth 0 looks towards the sun.")
    _add_atmosphere_argument(radiance)
    _add_sun_zeniths_argument(radiance)
    radiance.add_argument("--view-zenith", type=_number_list(checks.ZENITH_DEG), default=[0.0],
                          metavar="DEG,...",
                          help="view zenith angles in degrees (default 0)")
    radiance.add_argument("--view-azimuth", type=_number_list(checks.ANGLE_DEG), default=[0.0],
                          metavar="DEG,...", help="view azimuths relative to the sun in "
                          "degrees (default 0)")
    _add_rows_arguments(radiance)
    radiance.set_defaults(run=_radiance)

    irradiance = commands.add_parser(
        "irradiance", help="print spectral irradiance (direct, diffuse, global) as CSV or JSON",
        description="Print the spectral irradiance [W m^-2 nm^-1] at the observer: the sun's "
        "direct light on a surface facing it (direct_normal), the sky's on a horizontal "
        "surface (diffuse_horizontal) and their sum on the horizontal (global_horizontal), "
        "for each sun zenith angle and wavelength.")
    _add_atmosphere_argument(irradiance)
    _add_sun_zeniths_argument(irradiance)
    _add_rows_arguments(irradiance)
    irradiance.add_argument("--transmittance", action="store_true",
                            help="add the column direct_transmittance [-]: the direct beam's "
                            "transmittance, direct_normal / toa_irradiance")
    irradiance.add_argument("--tilt", type=_number(checks.ZENITH_DEG), default=None,
                            metavar="DEG", help="also the irradiance on a plane tilted DEG "
                            "from the horizontal (plane_direct, plane_sky_diffuse from the "
                            "sky's computed radiance distribution, plane_ground_reflected from "
                            "the config's ground albedo, plane_global; with "
                            "direct_transmittance)")
    irradiance.add_argument("--plane-azimuth", type=_number(checks.ANGLE_DEG), default=None,
                            metavar="DEG", help="the compass direction the tilted plane faces, "
                            "from north towards east (default 180: south)")
    irradiance.add_argument("--sun-azimuth", type=_number(checks.ANGLE_DEG), default=None,
                            metavar="DEG", help="the sun's azimuth from north towards east, "
                            "for --tilt (default 180; with --time the sun's own)")
    irradiance.set_defaults(run=_irradiance)
    _add_fit_command(commands)

    precompute = commands.add_parser(
        "precompute", help="precompute the scattering tables of an atmosphere into the cache",
        description="Precompute the tables (transmittance, single and multiple scattering, "
        "ground irradiance) that `render` and `radiance` use with the lut solver, and store "
        "them in the cache, so that later renders start at once. The cache entry is keyed by "
        "the atmosphere's optical profile, the orders, the table resolution, the wavelengths "
        "and the package version; a stale or damaged entry is recomputed.")
    _add_atmosphere_argument(precompute)
    precompute.add_argument("--wavelengths", default=None, metavar="N|LIST",
                            help="as for render: N bins over 360-830 nm or a list in nm "
                            f"(default {DEFAULT_WAVELENGTH_BINS} bins, what render uses); with "
                            "--monochromatic a list "
                            "as for radiance")
    precompute.add_argument("--monochromatic", action="store_true",
                            help="tables for `radiance` at exactly the listed wavelengths "
                            "(1 nm cells) rather than for images")
    precompute.add_argument("--orders", type=_orders, default=None,
                            help="scattering orders (default: the config's [tables] orders)")
    precompute.add_argument("--force", action="store_true",
                            help="recompute even when a valid entry is cached")
    _add_cache_arguments(precompute)
    precompute.set_defaults(run=_precompute)

    _add_export_tables_command(commands)

    view = commands.add_parser(
        "view", help="the real-time viewer in a web browser (WebGL2)",
        description="Start the interactive viewer: a local web server that sends the "
        "precomputed tables to a page which ray-casts them on the GPU every frame. Look "
        "around, fly up to orbit, move the sun by hand or from a date and place, change the "
        "aerosol, dust, ozone or ground albedo (the tables are recomputed: a preview in about "
        "a second, then the full tables). Binds 127.0.0.1 unless --host says otherwise. "
        "Ctrl-C stops it.")
    view.add_argument("atmosphere", metavar="PRESET_OR_CONFIG", nargs="?", default="earth",
                      help="the atmosphere shown first: a preset name (see `skyscatter "
                      "presets`) or a TOML file (default earth); the page offers the presets "
                      "too")
    view.add_argument("--port", type=_whole(0, 65535), default=0,
                      help="port to listen on (default 0: any free port)")
    view.add_argument("--host", default="127.0.0.1",
                      help="address to listen on (default 127.0.0.1, this computer only; "
                      "another address makes the viewer reachable from the network)")
    view.add_argument("--no-browser", action="store_true",
                      help="only serve; do not open the page in a browser")
    view.add_argument("--verbose", action="store_true", help="log every request")
    view.add_argument("--clouds", default=None, metavar="FILE|PRESET",
                      help="the clouds shown first: a clouds file or preset (cumulus, "
                      "stratocumulus, altocumulus, cirrus, stratus; docs/clouds.md); the page "
                      "offers the presets too (default: none)")
    _add_cache_arguments(view)
    view.set_defaults(run=_view)

    validate = commands.add_parser(
        "validate", help="run the validation suite and write a report with plots",
        description="Compare skyscatter with independent references - the Monte Carlo "
        "solver, DISORT, the CIE standard skies, SPECTRL2, published optical depths - and "
        "write report.md, summary.json and PNG plots into the output directory. Exits with 3 "
        f"when a check fails its limit. Cases: {', '.join(VALIDATION_CASES)}.")
    validate.add_argument("--quick", action="store_true",
                          help="the reduced suite: fewer angles, bands and paths (about 2 "
                          "minutes on 2 cores instead of about 6)")
    validate.add_argument("--output", type=Path, default=Path("validation"), metavar="DIR",
                          help="where the report goes (default: ./validation)")
    validate.add_argument("--cases", type=_name_list, default=None, metavar="LIST",
                          help="comma-separated subset of the cases (default: all)")
    validate.add_argument("--seed", type=_whole(0, 2**32 - 1), default=0,
                          help="seed of the Monte Carlo paths (default 0)")
    _add_cluster_arguments(validate, "(its workers must see --output: a shared file system; "
                           "default: the cases run here, one after the other)",
                           "to run the cases on at once (default: none, they run here, one "
                           "after the other)")
    _add_cache_arguments(validate)
    validate.set_defaults(run=_validate)

    _add_compare_command(commands)
    _add_sweep_command(commands)

    cache = commands.add_parser(
        "cache", help="list, size or clear the cache of precomputed tables",
        description="Inspect or empty the cache of precomputed tables (scattering tables, Mie "
        "tables, the star catalogue). The cache holds at most $SKYSCATTER_CACHE_MAX_BYTES "
        "(default 2G; units K, M, G, T are powers of 1024): after each new entry the least "
        "recently used ones are removed until the rest fit. Temporaries left by killed runs "
        "are removed by the next run that uses the cache.")
    cache.add_argument("action", choices=("list", "size", "clear"),
                       help="list: one line per entry, least recently used first (key, size, "
                       "last use, what it holds); size: the total and the limit; clear: "
                       "remove the entries (with --older-than only the old ones)")
    cache.add_argument("--older-than", type=float, default=None, metavar="DAYS",
                       help="clear: only the entries not used for DAYS days")
    cache.add_argument("--format", choices=("text", "json"), default="text",
                       help="list: output format (default text)")
    cache.add_argument("--cache-dir", type=Path, default=None, metavar="DIR",
                       help="the cache (default: $SKYSCATTER_CACHE_DIR, else "
                       "$XDG_CACHE_HOME/skyscatter or ~/.cache/skyscatter)")
    cache.set_defaults(run=_cache)

    compile_command = commands.add_parser(
        "compile", help="compile the numerical kernels now, so that no later run waits for it",
        description="Compile the numerical kernels (numba) into their cache on this machine by "
        "running the usual commands at a tiny size: about a minute of CPU, once. Without it "
        "the first render or radiance pays that minute. `make` runs it at install time.")
    compile_command.set_defaults(run=_compile)
    _add_completion_command(commands)
    _add_quiet_arguments(parser, commands)
    return parser


def _axis(bounds: Bounds) -> Callable[[str], list[float]]:
    """An argparse type: the numbers of a sweep axis, each within `bounds`: a list A,B,C (as
    `_float_list`) or a range START:STOP:COUNT[:log] (`api.parse_values`)."""
    def parse(text: str) -> list[float]:
        if ":" not in text:
            return _float_list(text, bounds)
        from skyscatter import api
        try:
            values = api.parse_values(text)
        except InputError as error:
            raise argparse.ArgumentTypeError(str(error)) from None
        return [_checked(bounds, value, repr(value)) for value in values]
    return parse


def _setting(text: str) -> tuple[str, str]:
    """'planet.ground_albedo=0,0.3' -> ('planet.ground_albedo', '0,0.3') (argparse type)."""
    key, equals, values = text.partition("=")
    if not equals or not key.strip() or not values.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is not KEY=VALUES; give e.g. "
                                         "planet.ground_albedo=0,0.1,0.3")
    return key.strip(), values.strip()


def _add_cluster_arguments(command: argparse.ArgumentParser, scheduler_default: str,
                           workers_default: str) -> None:
    """--scheduler and --workers: the Dask cluster a command runs on (`dask_cluster`)."""
    command.add_argument("--scheduler", default=None, metavar="ADDRESS",
                         help="run on the Dask cluster of this scheduler (tcp://HOST:8786), "
                         "whose workers have skyscatter installed; needs `pip install "
                         f"\"skyscatter[dask]\"` {scheduler_default}")
    command.add_argument("--workers", type=_whole(1, 1024), default=None, metavar="N",
                         help=f"worker processes of a local Dask cluster {workers_default}")


def _add_sweep_command(commands: argparse._SubParsersAction) -> None:
    sweep = commands.add_parser(
        "sweep", help="compute radiance and irradiance over a grid of config values and "
        "geometries on a Dask cluster, into one NetCDF or Zarr dataset",
        description="Compute the diffuse sky radiance (and, with the lut and single solvers, "
        "the direct and diffuse surface irradiance) for every combination of config values "
        "(--set KEY=VALUES, repeatable), sun zenith (or time: --start/--end/--step at "
        "--lat/--lon), view zenith, azimuth and wavelength, as one labelled dataset "
        "(docs/sweep.md). Runs on a local Dask cluster (--workers "
        "processes) or an existing one (--scheduler); each atmosphere's tables are built once. "
        "Finished chunks are kept in OUT.parts/ beside the output, so running the same "
        "command again after an interruption computes only what is missing. Needs `pip "
        "install \"skyscatter[dask]\"`. Example: skyscatter sweep earth --set "
        "constituent[2].optics.optical_depth=0.02:0.8:5 --set planet.ground_albedo=0,0.3 "
        "--sun-zenith 0:80:5 --view-zenith 0:85:18 --azimuth 0:180:7 -o lut.nc")
    _add_atmosphere_argument(sweep)
    sweep.add_argument("--set", dest="settings", type=_setting, action="append", default=[],
                       metavar="KEY=VALUES",
                       help="a config value to sweep, by dotted key (planet.ground_albedo, "
                       "constituent[2].optics.optical_depth), over VALUES: A,B,C, "
                       "START:STOP:COUNT (ends included) or START:STOP:COUNT:log; repeat for "
                       "more axes (the dataset's dimensions, in this order)")
    sweep.add_argument("--sun-zenith", type=_axis(checks.ZENITH_DEG), default=None,
                       metavar="VALUES", help="sun zenith angles in degrees, as VALUES "
                       "(default 30; or the sun's at the times of --start/--end)")
    _add_time_range_arguments(sweep, "time", required=False)
    sweep.add_argument("--lat", type=_number(checks.LATITUDE_DEG), default=None, metavar="DEG",
                       help="observer latitude in degrees, north positive (with --start; "
                       "Earth and Mars presets)")
    sweep.add_argument("--lon", type=_number(checks.ANGLE_DEG), default=None, metavar="DEG",
                       help="observer longitude in degrees, east positive (with --start)")
    sweep.add_argument("--view-zenith", type=_axis(checks.ZENITH_DEG), default=[0.0],
                       metavar="VALUES", help="view zenith angles in degrees, 0 straight up "
                       "(default 0)")
    sweep.add_argument("--azimuth", type=_axis(checks.ANGLE_DEG), default=[0.0],
                       metavar="VALUES", help="view azimuths in degrees relative to the sun, "
                       "0 towards it, also over times (default 0)")
    sweep.add_argument("--wavelengths", type=_axis(checks.ANY_NUMBER),
                       default=[440.0, 550.0, 680.0], metavar="VALUES",
                       help="wavelengths in nm, each a 1 nm cell, within 280.5-1690 "
                       "(default 440,550,680)")
    sweep.add_argument("--elevation-m", "--altitude", dest="altitude",
                       type=_number(checks.ELEVATION_M), default=0.0, metavar="M",
                       help="observer height above the ground in metres (default 0)")
    _add_solver_arguments(sweep, 64)
    sweep.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                       help="the dataset: OUT.nc (NetCDF-3) or OUT.zarr (a Zarr store)")
    _add_cluster_arguments(sweep, "(default: a local cluster)",
                           "(default: the CPU cores)")
    sweep.add_argument("--memory-limit", default=None, metavar="SIZE",
                       help="memory per local worker, e.g. 4GiB (default: Dask's, the memory "
                       "shared among the workers)")
    sweep.add_argument("--restart", action="store_true",
                       help="discard the finished chunks of an earlier run in OUT.parts/ and "
                       "start afresh (default: resume from them)")
    sweep.add_argument("--keep-parts", action="store_true",
                       help="keep OUT.parts/ after the dataset is written")
    sweep.set_defaults(run=_sweep)


def _sweep(args: argparse.Namespace) -> None:
    import shlex
    import time

    from skyscatter import api
    from skyscatter.cli_progress import progress

    values: dict[str, str] = {}
    for key, text in args.settings:
        if key in values:
            raise InputError(f"--set {key} is given twice; give each key once, with all its "
                             "values", key="set", value=key)
        values[key] = text
    times = None
    if args.start is not None or args.end is not None:
        if args.start is None or args.end is None:
            raise InputError("a sweep over times needs both --start and --end (ISO 8601 with "
                             "a time zone)", key="start", value=(args.start, args.end))
        if args.sun_zenith is not None:
            raise InputError("--sun-zenith and --start/--end both place the sun: give one",
                             key="sun_zenith", value=args.sun_zenith)
        times = _time_steps(args)
    elif args.step is not None or args.frames is not None:
        raise InputError("--step and --frames space the times of --start/--end: give those "
                         "too", key="step", value=args.step or args.frames)
    elif args.lat is not None or args.lon is not None:
        raise InputError("--lat and --lon are the place of a sweep over times: give --start "
                         "and --end too", key="lat", value=(args.lat, args.lon))
    start = time.perf_counter()
    with progress(1, "sweep", unit="chunk") as bar:
        def advance(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        result = api.sweep(
            args.atmosphere, values, args.sun_zenith, args.view_zenith, args.azimuth,
            times=times, latitude_deg=args.lat, longitude_deg=args.lon,
            wavelengths_nm=args.wavelengths, output_path=args.output, altitude_m=args.altitude,
            solver=args.solver, orders=args.orders, n_samples=args.samples,
            cache_dir=args.cache_dir, use_cache=not args.no_cache, scheduler=args.scheduler,
            workers=args.workers, memory_limit=args.memory_limit, restart=args.restart,
            keep_parts=args.keep_parts, allow_large=args.allow_large,
            command=shlex.join(["skyscatter", *args.command_line]), on_chunk=advance)
    sizes = " x ".join(f"{size} {name}" for name, size in result.dataset.sizes.items())
    reused = f", {result.reused} reused from {args.output}.parts" if result.reused else ""
    print(f"wrote {result.output}: {sizes}; {result.computed} chunks computed{reused} in "
          f"{time.perf_counter() - start:.0f} s", file=sys.stderr)


def _add_compare_command(commands: argparse._SubParsersAction) -> None:
    compare = commands.add_parser(
        "compare", help="compare the sky models with the Monte Carlo reference: errors, "
        "time, memory, renders",
        description="Run several solvers over the same atmospheres and sun zenith angles and "
        "write report.md, results.json and PNG figures into the output directory: per "
        "solver, atmosphere, sun zenith and band the relative radiance error against the "
        "Monte Carlo reference (median, 95th percentile) on a grid of view directions from "
        "the ground, the luminance and chromaticity error, the precompute time, the CPU time "
        "of a 1920 x 1080 frame, the peak memory, fisheye renders side by side with error "
        "images, and what each solver cannot do. A solver outside its domain for a case "
        "shows n/a (domain). The Monte Carlo means are cached, so a rerun is fast. "
        "docs/techniques.md shows a run.")
    compare.add_argument("--solvers", type=_name_list, default=None, metavar="LIST",
                         help="comma-separated solvers (default: all but montecarlo, the "
                         "reference, and single: lut,hillaire,schuler,bruneton-simplified,"
                         "cie,preetham)")
    compare.add_argument("--atmospheres", type=_name_list, default=None, metavar="LIST",
                         help="comma-separated presets, TOML files or NAME:CONSTITUENT*FACTOR "
                         "variants (default: earth,earth:aerosol*4,mars-physical - clear "
                         "Earth, a hazy Earth with 4 x the aerosol, dusty Mars)")
    compare.add_argument("--sun-zeniths", type=_number_list(checks.ZENITH_DEG), default=None,
                         metavar="DEG,...", help="sun zenith angles in degrees, above 90 in "
                         "twilight (default 0,30,60,80,94)")
    compare.add_argument("--quick", action="store_true",
                         help="a small run for tests: 10 directions, 2 bands, 2000 paths, a "
                         "384 x 216 frame scaled to 1920 x 1080, tables from the cache")
    compare.add_argument("--paths", type=_whole(100, 1_000_000), default=None,
                         help="Monte Carlo paths per direction and band with the sun up (2.5 x "
                         "below the horizon; default 4000, --quick 2000)")
    compare.add_argument("-o", "--output", type=Path, default=Path("comparison"), metavar="DIR",
                         help="where the report goes (default: ./comparison)")
    compare.add_argument("--seed", type=_whole(0, 2**32 - 1), default=0,
                         help="seed of the Monte Carlo paths (default 0)")
    _add_cache_arguments(compare)
    compare.set_defaults(run=_compare)


def _compare(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.cli_progress import progress

    if args.output.exists() and not args.output.is_dir():
        raise InputError(f"--output {args.output} is a file; give a directory",
                         key="output", value=str(args.output))

    def log(message: str) -> None:
        print(f"skyscatter: {message}", file=sys.stderr, flush=True)

    with progress(0, "comparing", unit="case") as bar:
        def step(done: int, total: int, label: str) -> None:
            bar.total = total
            bar.set_postfix_str(label, refresh=False)
            bar.update(done - bar.n)
        result = api.compare_techniques(
            args.output, args.solvers, args.atmospheres, args.sun_zeniths, quick=args.quick,
            paths=args.paths, cache_dir=args.cache_dir, use_cache=not args.no_cache,
            seed=args.seed, log=log, step=step)
    print(f"report: {result.files[0]}, results: {result.files[1]}, "
          f"{len(result.files) - 2} figures")


def _add_completion_command(commands: argparse._SubParsersAction) -> None:
    from skyscatter.cli_completion import SHELLS
    completion = commands.add_parser(
        "completion", help="print a shell completion script (bash, zsh, fish)",
        description="Print a script that completes skyscatter's commands, options, choices and "
        "preset names in your shell. bash: `source <(skyscatter completion bash)` (or save it "
        "to ~/.local/share/bash-completion/completions/skyscatter); zsh, after compinit: "
        "`source <(skyscatter completion zsh)`; fish: `skyscatter completion fish > "
        "~/.config/fish/completions/skyscatter.fish`.")
    completion.add_argument("shell", choices=SHELLS, help="the shell")
    completion.set_defaults(run=_completion)


def _ground_half(text: str) -> str | float:
    """--ground: "tables", "black" or an albedo from 0 to 1."""
    if text in ("tables", "black"):
        return text
    try:
        albedo = float(text)
    except ValueError:
        albedo = math.nan
    if not 0.0 <= albedo <= 1.0:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not tables, black or an albedo from 0 to 1")
    return albedo


def _add_ground_argument(command: argparse.ArgumentParser) -> None:
    command.add_argument(
        "--ground", type=_ground_half, default="tables", metavar="tables|black|ALBEDO",
        help="below the horizon: the ground as the atmosphere's tables see it (default), "
        "black (for a map whose lower half the engine draws), or a grey ground of this albedo "
        "(0-1) in place of the config's, which lights the sky too (new tables)")


def _with_ground(atmosphere, ground: str | float):
    """The atmosphere over the ground of --ground ALBEDO, else as it is."""
    from skyscatter import api
    return atmosphere if isinstance(ground, str) else api.with_ground_albedo(atmosphere, ground)


def _add_quiet_arguments(parser: argparse.ArgumentParser,
                         commands: argparse._SubParsersAction) -> None:
    """-q/--quiet before or after the command (`_stderr_unless_quiet`)."""
    text = "print only errors on stderr: no progress bars, no notes"
    parser.add_argument("-q", "--quiet", action="store_true", help=text)
    for command in commands.choices.values():  # the command's flag sets it, its absence not
        command.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                             help=text)


def _completion(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.cli_completion import completion_script
    values = {"atmosphere": list(api.list_presets()), "solver": list(solver_descriptions()),
              "clouds": list(api.list_cloud_presets()), "terrain": ["demo"]}
    sys.stdout.write(completion_script(build_parser(), args.shell, values=values))


@contextmanager
def _stderr_unless_quiet(quiet: bool) -> Iterator[None]:
    """With `quiet`, the run's notes and progress bars (stderr) go nowhere; main still prints
    the error that ends a run, after this block."""
    if not quiet:
        yield
        return
    with open(os.devnull, "w") as sink, redirect_stderr(sink):
        yield


def _compile(args: argparse.Namespace) -> None:
    from skyscatter.compile_ahead import compile_kernels
    seconds = compile_kernels(main, lambda line: print(line, flush=True))
    print(f"compiled in {seconds:.0f} s; later runs load the kernels from the cache")


def _presets(args: argparse.Namespace) -> None:
    from skyscatter.api import describe_gas, list_presets, load_atmosphere
    presets = list_presets()
    width = max(len(name) for name in presets)
    for name, description in presets.items():
        print(f"{name:<{width}}  {description}")
        if args.verbose:
            for gas in describe_gas(load_atmosphere(name)):
                print(_gas_summary(gas, " " * (width + 2)))


def _gas_summary(gas: dict, indent: str) -> str:
    """Lines describing one `api.describe_gas` entry."""
    composition = ", ".join(f"{name} {fraction:.4g}" for name, fraction in
                            sorted(gas["composition"].items(), key=lambda item: -item[1]))
    tau = ", ".join(f"{value:.3g} ({wavelength:g} nm)"
                    for wavelength, value in gas["rayleigh_optical_depth"].items())
    return "\n".join(indent + line for line in (
        f"[gas] '{gas['name']}': {composition}; M = {gas['molar_mass_g_mol']:.4g} g/mol",
        f"T = {gas['surface_temperature_k']:g} K, P = {gas['surface_pressure_pa']:.6g} Pa, "
        f"g = {gas['gravity_m_s2']:.4g} m/s^2 -> N0 = {gas['surface_number_density_m3']:.4g} "
        f"m^-3, rho = {gas['surface_mass_density_kg_m3']:.4g} kg/m^3, "
        f"H = {gas['scale_height_m']:.0f} m",
        f"column {gas['column_m2']:.4g} m^-2 ({gas['mass_column_kg_m2']:.4g} kg/m^2); "
        f"Rayleigh optical depth {tau}"))


def _render(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.cli_progress import progress

    image_target = _image_target(args.output)
    image_options = api.ImageOptions(
        ev100=args.exposure, compensation_ev=args.exposure_compensation, operator=args.tonemap,
        colour_space=args.colour_space, balance_to_light=args.white_balance == "star",
        exr_content=args.exr_content, adapt_to_night=args.time is not None)
    api.check_image_options(png_path=image_target, exr_path=args.exr,
                            options=image_options)  # the outputs can be written: before any work
    if args.light is not None:
        if args.camera not in WHOLE_SPHERE:
            raise InputError("--light needs an image of the whole sphere: add --camera cubemap "
                             f"(or {', '.join(WHOLE_SPHERE[1:])})", key="light",
                             value=str(args.light))
        check_writable_file(args.light)
    atmosphere = _with_ground(api.load_atmosphere(args.atmosphere), args.ground)
    observer = _observer(args) if args.time is not None else None
    summary = None
    if observer is not None:  # checks that the planet has an ephemeris before any table work
        summary = _sky_summary(api.sky_ephemeris(atmosphere, observer))
    zenith = (args.sun_zenith if args.sun_zenith is not None
              else 90.0 - (30.0 if args.sun_elevation is None else args.sun_elevation))
    orbit = args.camera == "orbit"
    altitude = args.altitude
    radius = atmosphere.planet.radius_m
    latitude = 0.0 if args.lat is None else args.lat
    longitude = 0.0 if args.lon is None else args.lon
    if orbit:
        altitude = radius if args.distance_km is None else args.distance_km * 1000.0
        camera = _orbit_camera(args, altitude, radius, latitude, longitude)
    elif args.look_at is not None:
        raise InputError("--look-at is for --camera orbit; aim other cameras with --heading "
                         "and --pitch", key="look_at", value=args.look_at)
    else:
        camera = _camera(args)
    if args.mips is not None:
        api.check_mip_chain(camera, args.mips, args.exr, args.exr_content)
    api.check_render_cost(camera, args.wavelengths, solver=args.solver, n_samples=args.samples,
                          allow_large=args.allow_large)  # memory and time, before allocating
    ground = _ground(args, radius)
    clouds = _clouds(args)
    objects = _sky_objects(args)  # checked before the tables are computed
    with _solver_options(args, atmosphere) as options, progress(
            int(camera.valid_mask().sum()), "rendering", unit="ray") as bar:
        if observer is not None:
            image = api.render_at(atmosphere, camera, observer, objects=objects,
                                  wavelengths_nm=args.wavelengths, solver=args.solver,
                                  options=options, progress=bar.update,
                                  orbit_altitude_m=altitude if orbit else None, ground=ground,
                                  allow_large=args.allow_large, clouds=clouds)
        else:
            image = api.render(atmosphere, camera, zenith, sun_azimuth_deg=args.sun_azimuth,
                               altitude_m=altitude, wavelengths_nm=args.wavelengths,
                               solver=args.solver, options=options, progress=bar.update,
                               orbit_latitude_deg=latitude if orbit else None,
                               orbit_longitude_deg=longitude, ground=ground,
                               allow_large=args.allow_large, clouds=clouds,
                               cloud_time_s=args.cloud_time, sun_disk=not args.no_sun_disk)
    if args.ground == "black":
        image = api.without_ground(image, camera, atmosphere, altitude)
    ev100 = api.save_image(image, image_target, args.exr, options=image_options)
    written = ["the PNG to standard output" if image_target is not args.output
               else str(args.output)] + ([str(args.exr)] if args.exr else [])
    if args.light is not None:
        light = api.environment_light(image, camera, args.colour_space,
                                      balance_to_light=image_options.balance_to_light)
        atomic_write(args.light, lambda path: Path(path).write_text(
            json.dumps(light, indent=1, allow_nan=False) + "\n", encoding="utf-8"))
        written.append(str(args.light))
    if args.mips is not None:
        written += [str(path) for path in api.save_mip_chain(image, camera, args.exr, args.mips,
                                                             options=image_options)]
    print(f"wrote {', '.join(written)} (EV100 {ev100:.2f})", file=sys.stderr)
    if summary is not None:
        print(summary, file=sys.stderr)


def _image_target(output: Path):
    """Where `-o` sends the display image: the path, or for `-` standard output (refused on a
    terminal, which binary PNG data would garble)."""

    if str(output) != "-":
        return output
    if sys.stdout.isatty():
        raise InputError("-o -: standard output is a terminal; redirect it to a file or a pipe "
                         "(skyscatter render ... -o - > sky.png)", key="output", value="-")
    return sys.stdout.buffer


def _observer(args: argparse.Namespace, time: str | None = None):
    """The Observer of --time (or `time`), --lat, --lon, --elevation-m."""
    from skyscatter import api

    if args.lat is None or args.lon is None:
        raise InputError("--time needs the place too: give --lat and --lon in degrees (north "
                         "and east positive)", key="lat", value=(args.lat, args.lon))
    return api.make_observer(args.time if time is None else time, args.lat, args.lon,
                             args.altitude)


def _sky_objects(args: argparse.Namespace):
    import numpy as np

    from skyscatter import api

    twinkle = None if args.twinkle is None else np.random.default_rng(args.twinkle)
    return api.SkyObjects(stars=not args.no_stars, moon=not args.no_moon,
                          milky_way=args.milky_way, airglow=not args.no_airglow,
                          magnitude_limit=args.magnitude_limit,
                          scintillation=twinkle, sun_disk=not getattr(args, "no_sun_disk", False))


def _sky_summary(sky) -> str:
    """One line on where the sun (and moon) stand."""
    line = (f"sun: altitude {sky.sun.altitude_deg:.2f} deg, azimuth {sky.sun.azimuth_deg:.2f} "
            f"deg, distance {sky.sun.distance_m / AU_M:.5f} AU")
    if sky.moon is not None:
        line += (f"; moon: altitude {sky.moon.altitude_deg:.2f} deg, azimuth "
                 f"{sky.moon.azimuth_deg:.2f} deg")
    return line


def _time_steps(args: argparse.Namespace) -> list:
    """The times of --start, --end and --step or --frames (default 60)."""
    import datetime

    from skyscatter import api

    start, end = api.parse_time(args.start), api.parse_time(args.end)
    if not end > start:
        raise InputError(f"--end {args.end} must come after --start {args.start}", key="end",
                         value=args.end)
    span = (end - start).total_seconds()
    if args.step is not None and span / args.step >= api.MAX_FRAMES:
        raise InputError(f"--step {args.step:g} s over {span:g} s would make more than "
                         f"{api.MAX_FRAMES} frames; give a longer --step", key="step",
                         value=args.step, allowed=f"at most {api.MAX_FRAMES} frames")
    if args.step is not None:
        count = int(span // args.step) + 1
    else:
        count = args.frames if args.frames is not None else 60
    step = args.step if args.step is not None else span / max(count - 1, 1)
    return [start + datetime.timedelta(seconds=i * step) for i in range(count)]


def _add_time_range_arguments(command: argparse.ArgumentParser, unit: str,
                              required: bool = True) -> None:
    """--start, --end and --step or --frames (`_time_steps`)."""
    command.add_argument("--start", required=required, metavar="ISO8601",
                         help=f"first {unit}'s time with a time zone")
    command.add_argument("--end", required=required, metavar="ISO8601",
                         help=f"last {unit}'s time with a time zone")
    steps = command.add_mutually_exclusive_group()
    steps.add_argument("--step", type=_duration_s, default=None, metavar="DURATION",
                       help=f"time between {unit}s: 30s, 10min, 1h ... (default: 60 {unit}s)")
    steps.add_argument("--frames", type=_frame_count, default=None, metavar="N",
                       help=f"number of {unit}s, evenly spread from --start to --end")


def _add_envmap_command(commands) -> None:
    envmap = commands.add_parser(
        "envmap", help="write environment maps over a time range, with their light and an index",
        description="Render environment maps of the whole sky over a time range at one place, "
        "reusing the precomputed tables: a linear map (EXR or Radiance .hdr), the sun and the "
        "SH irradiance (light JSON) and optionally the specular mip chain for each time, and "
        "index.json listing the times, files and the sun (docs/engines.md). Example: "
        "skyscatter envmap earth --start 2024-06-21T04:00+02:00 --end 2024-06-21T22:00+02:00 "
        "--step 1h --lat 52.52 --lon 13.40 -o berlin_maps")
    envmap.add_argument("atmosphere", metavar="PRESET_OR_CONFIG",
                        help="an Earth or Mars preset, or a TOML file with [planet] body")
    _add_time_range_arguments(envmap, "map")
    _add_place_arguments(envmap, required=True)
    envmap.add_argument("--camera", choices=WHOLE_SPHERE, default="cubemap",
                        help="the map's projection (as for render; default cubemap)")
    envmap.add_argument("--size", type=_size, default=128, metavar="PIXELS",
                        help="a cube face's side, or the image height (default 128)")
    envmap.add_argument("--cube-layout", choices=tuple(CUBE_LAYOUTS), default="cross",
                        help="cubemap faces: cross or strip (default cross)")
    envmap.add_argument("--format", choices=("exr", "hdr"), default="exr",
                        help="the maps' file format: OpenEXR or Radiance RGBE (default exr)")
    envmap.add_argument("--mips", type=int, default=None, metavar="LEVELS",
                        help="also write each cube map's GGX-prefiltered mip chain (as render)")
    envmap.add_argument("--colour-space", default="srgb",
                        help="srgb (default), rec709, display-p3, rec2020, acescg or "
                        "aces2065-1")
    _add_wavelength_argument(envmap)
    _add_solver_arguments(envmap, 64)
    _add_cloud_argument(envmap)
    _add_sky_object_arguments(envmap)
    _add_ground_argument(envmap)
    envmap.add_argument("--no-sun-disk", action="store_true",
                        help="leave the sun's disk out of the maps (it stays in the light file)")
    envmap.add_argument("-o", "--output", type=Path, default=Path("envmaps"), metavar="DIR",
                        help="the folder of maps (default envmaps); it holds only this "
                        "command's files and is replaced as a whole when the run completes")
    envmap.set_defaults(run=_envmap)


def _envmap(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.cli_progress import progress

    times = _time_steps(args)
    atmosphere = _with_ground(api.load_atmosphere(args.atmosphere), args.ground)
    api.sky_ephemeris(atmosphere, _observer(args, args.start))  # checks before the tables
    camera = _camera(args)
    objects = _sky_objects(args)
    with _solver_options(args, atmosphere) as options, progress(len(times), "maps",
                                                                unit="map") as bar:
        index = api.environment_series(
            atmosphere, camera, times, args.lat, args.lon, out_dir=args.output,
            elevation_m=args.altitude, suffix=f".{args.format}", mips=args.mips,
            objects=objects, wavelengths_nm=args.wavelengths, solver=args.solver,
            options=options, image=api.ImageOptions(colour_space=args.colour_space),
            on_frame=lambda *_: bar.update(1), allow_large=args.allow_large,
            clouds=_clouds(args), black_ground=args.ground == "black")
    print(f"wrote {len(index['maps'])} maps and index.json in {args.output}", file=sys.stderr)


def _timelapse(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.cli_progress import progress

    api.check_image_options(args.tonemap, args.colour_space)
    times = _time_steps(args)
    count = len(times)
    atmosphere = api.load_atmosphere(args.atmosphere)
    api.sky_ephemeris(atmosphere, _observer(args, args.start))  # checks before the tables
    camera = _camera(args)
    api.check_render_cost(camera, args.wavelengths, solver=args.solver, n_samples=args.samples,
                          allow_large=args.allow_large, frames=count)
    frames_dir = args.frames_dir or args.output.with_name(f"{args.output.stem}_frames")
    objects = _sky_objects(args)
    with _solver_options(args, atmosphere) as options, progress(count, "time-lapse",
                                                                unit="frame") as bar:
        result = api.timelapse(
            atmosphere, camera, times, args.lat, args.lon, video_path=args.output,
            frames_dir=frames_dir, elevation_m=args.altitude, fps=args.fps, objects=objects,
            wavelengths_nm=args.wavelengths, solver=args.solver, options=options,
            image=api.ImageOptions(compensation_ev=args.exposure_compensation,
                                   operator=args.tonemap, colour_space=args.colour_space),
            adaptation_time_s=args.adaptation_minutes * 60.0,
            on_frame=lambda *_: bar.update(1), allow_large=args.allow_large,
            clouds=_clouds(args), scheduler=args.scheduler, workers=args.workers)
    print(f"wrote {result.video} and {len(result.frames)} frames in {frames_dir} (EV100 "
          f"{min(result.ev100):.1f} to {max(result.ev100):.1f})", file=sys.stderr)


def _orbit_camera(args: argparse.Namespace, altitude_m: float, radius_m: float,
                  latitude_deg: float, longitude_deg: float):
    """Perspective camera `altitude_m` above --lat/--lon, looking at the planet's centre or at
    --look-at, north up."""
    from skyscatter import api
    fov = args.fov if args.fov is not None else api.orbit_field_of_view_deg(altitude_m,
                                                                            radius_m)
    if args.look_at is None:
        return api.PerspectiveCamera(args.size, args.size, fov, heading_deg=0.0,
                                     pitch_deg=-90.0)
    latitude, longitude, altitude_km = args.look_at
    viewpoint = api.viewpoint_at(altitude_m, radius_m, latitude_deg, longitude_deg)
    forward = api.look_at_direction(viewpoint, latitude, longitude, altitude_km * 1000.0,
                                    radius_m)
    up = (0.0, 0.0, 1.0) if abs(forward[2]) < 0.99 else (0.0, 1.0, 0.0)  # level horizon
    width = max(1, round(args.size * args.aspect))
    return api.PerspectiveCamera.from_forward_up(width, args.size, fov, forward, up)


def _add_cloud_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--clouds", default=None, metavar="FILE|PRESET",
                        help="cloud layers: a TOML file or a preset (cumulus, stratocumulus, "
                        "altocumulus, cirrus, stratus, earth-weather for views from space; "
                        "docs/clouds.md); table solver only")


def _clouds(args: argparse.Namespace):
    """The Clouds of --clouds, or None; checked before any table work."""
    from skyscatter import api
    if args.clouds is None:
        return None
    if args.solver != "lut":
        raise InputError("--clouds needs the table solver (--solver lut)", key="solver",
                         value=args.solver, allowed="lut")
    return api.load_clouds(args.clouds)


def _ground(args: argparse.Namespace, radius_m: float):
    """The albedo map and terrain of --albedo-map/--terrain, or None."""
    from skyscatter import api
    if args.albedo_map is None and args.terrain is None:
        return None
    terrain = None
    if args.terrain == "demo":
        terrain = api.demo_mountains(peak_m=args.terrain_height, spacing_m=args.terrain_spacing,
                                     planet_radius_m=radius_m)
    elif args.terrain is not None:
        terrain = api.Heightfield.from_image(args.terrain, args.terrain_spacing,
                                             args.terrain_height, radius_m)
    albedo = None if args.albedo_map is None else api.AlbedoMap.from_image(args.albedo_map)
    return api.Ground(albedo_map=albedo, terrain=terrain)


@contextmanager
def _solver_options(args: argparse.Namespace, atmosphere) -> Iterator:
    """Solver options from --orders/--samples/--cache-dir/--no-cache/--force, with a progress
    bar for the tables' precomputation and a log line saying where they came from."""
    from skyscatter import api
    from skyscatter.cli_progress import progress

    with progress(1, "precomputing tables", unit="step") as bar:
        def advance(done: int, total: int, stage: str) -> None:
            bar.total = total
            bar.set_postfix_str(stage, refresh=False)
            bar.update(done - bar.n)

        def log(message: str) -> None:
            bar.write(f"skyscatter: {message}", file=sys.stderr)

        yield api.solver_options(atmosphere, orders=args.orders,
                                 n_samples=getattr(args, "samples", 64),
                                 cache_dir=args.cache_dir, use_cache=not args.no_cache,
                                 force=getattr(args, "force", False), progress=advance, log=log)


def _camera(args: argparse.Namespace):
    from skyscatter import api
    if args.camera == "fisheye":
        return api.FisheyeCamera(args.size)
    if args.camera == "panorama":
        return api.EquirectangularCamera(2 * args.size, args.size,
                                         heading_deg=getattr(args, "heading", 180.0))
    if args.camera == "cubemap":
        return api.CubeMapCamera(args.size, args.cube_layout)
    if args.camera == "octahedral":
        return api.OctahedralCamera(args.size)
    if args.camera == "sphere":
        return api.SphereMapCamera(args.size)
    if args.camera == "paraboloid":
        return api.ParaboloidCamera(args.size)
    width = max(1, round(args.size * args.aspect))
    fov = 60.0 if args.fov is None else args.fov
    return api.PerspectiveCamera(width, args.size, fov, heading_deg=args.heading,
                                 pitch_deg=args.pitch)


def _sun_zeniths(args: argparse.Namespace, atmosphere) -> tuple[list[float], object]:
    """(--sun-zenith, None), or the sun's zenith angle at --time for --lat/--lon and the
    `api.sky_ephemeris` it comes from (said on stderr)."""
    from skyscatter import api
    if args.time is None:
        return args.sun_zenith, None
    sky = api.sky_ephemeris(atmosphere, _observer(args))
    print(_sky_summary(sky), file=sys.stderr)
    return [sky.sun_zenith_deg], sky


def _sun_distance(sky) -> float | None:
    """The sun's distance [m] at --time (`_sun_zeniths`'s ephemeris), None without a date."""
    return None if sky is None else sky.sun.distance_m


def _radiance(args: argparse.Namespace) -> None:
    from skyscatter import api
    output_format = _rows_format(args)
    atmosphere = api.load_atmosphere(args.atmosphere)
    sun_zenith, sky = _sun_zeniths(args, atmosphere)
    with _solver_options(args, atmosphere) as options:
        if output_format == "netcdf":
            api.write_netcdf(api.radiance_dataset(
                atmosphere, sun_zenith, args.view_zenith, args.view_azimuth, args.wavelengths,
                altitude_m=args.altitude, solver=args.solver, options=options,
                allow_large=args.allow_large, sun_distance_m=_sun_distance(sky)), args.output)
            return
        rows = api.sky_radiance_rows(atmosphere, sun_zenith, args.view_zenith,
                                     args.view_azimuth, args.wavelengths,
                                     altitude_m=args.altitude, solver=args.solver,
                                     options=options, allow_large=args.allow_large,
                                     sun_distance_m=_sun_distance(sky))
        geometry = {"view_zeniths_deg": args.view_zenith,
                    "relative_azimuths_deg": args.view_azimuth}
        _write_rows(args, output_format, rows, _rows_metadata(args, atmosphere, rows, options,
                                                              sun_zenith, geometry, sky))


def _irradiance(args: argparse.Namespace) -> None:
    from skyscatter import api
    output_format = _rows_format(args)
    if args.time is not None and args.sun_azimuth is not None:
        raise InputError("--sun-azimuth and --time both place the sun: give one",
                         key="sun_azimuth", value=args.sun_azimuth)
    for name in ("plane_azimuth", "sun_azimuth"):
        if args.tilt is None and getattr(args, name) is not None:
            raise InputError(f"--{name.replace('_', '-')} is for the plane of --tilt: give "
                             "--tilt DEG too", key=name, value=getattr(args, name))
    atmosphere = api.load_atmosphere(args.atmosphere)
    sun_zenith, sky = _sun_zeniths(args, atmosphere)
    sun_azimuth = 180.0 if args.sun_azimuth is None else args.sun_azimuth
    if sky is not None:
        sun_azimuth = sky.sun.azimuth_deg
    plane = {} if args.tilt is None else {"tilt_deg": args.tilt,
                                          "plane_azimuth_deg": 180.0 if args.plane_azimuth
                                          is None else args.plane_azimuth,
                                          "sun_azimuth_deg": sun_azimuth}
    with _solver_options(args, atmosphere) as options:
        if output_format == "netcdf":
            api.write_netcdf(api.irradiance_dataset(
                atmosphere, sun_zenith, args.wavelengths, altitude_m=args.altitude,
                solver=args.solver, options=options, sun_distance_m=_sun_distance(sky),
                **plane), args.output)
            return
        rows = api.irradiance_rows(atmosphere, sun_zenith, args.wavelengths,
                                   altitude_m=args.altitude, solver=args.solver, options=options,
                                   transmittance=args.transmittance,
                                   sun_distance_m=_sun_distance(sky), **plane)
        _write_rows(args, output_format, rows,
                    _rows_metadata(args, atmosphere, rows, options, sun_zenith, plane, sky))


def _add_fit_command(commands) -> None:
    fit = commands.add_parser(
        "fit", help="estimate config values from measured radiances, transmittances, colours",
        description="Estimate config values (the --free keys, within their bounds) from "
        "measurements with uncertainties: sky radiances, direct-sun transmittances and sky "
        "chromaticities in one CSV or JSON file (docs/fit.md; the output of `radiance` is "
        "one). Bounded least squares on a fast forward model (a solver, or interpolation in "
        "a sweep with --model), each residual weighted by the measurement's uncertainty and "
        "the model's stated error; optionally refined with the tables and checked by an "
        "exact solver at the answer. Prints the estimates with 1-sigma uncertainties; -o "
        "writes the whole report (covariance, correlation, chi-square, residuals per row, "
        "what the data cannot constrain and why, time) as JSON.")
    _add_atmosphere_argument(fit)
    fit.add_argument("measurements", type=Path, metavar="MEASUREMENTS", nargs="?",
                     default=None, help="CSV or JSON file of measurement rows (docs/fit.md); "
                     "optional with --image")
    fit.add_argument("--free", action="append", required=True, metavar="KEY=LOW:HIGH[:START]",
                     help="a config value to fit, by dotted key, with its bounds and start "
                     "(default: the config's value), e.g. "
                     "constituent[2].optics.optical_depth=0.01:1:0.1; repeat for more")
    fit.add_argument("--solver", default="hillaire", metavar="NAME",
                     help="the fast forward model: hillaire (default), schuler, single or lut")
    fit.add_argument("--model", type=Path, default=None, metavar="SWEEP",
                     help="interpolate in this sweep (NetCDF/Zarr of `skyscatter sweep`) "
                     "instead of running --solver")
    fit.add_argument("--refine", default=None, choices=["lut"],
                     help="fit again with the tables, from the fast fit's answer")
    fit.add_argument("--check", action="append", default=[], choices=["lut", "montecarlo"],
                     help="evaluate this exact solver at the answer (residuals per row); "
                     "repeatable")
    fit.add_argument("--samples", type=_samples, default=512,
                     help="ray-marching samples per view ray of the solvers (default 512, "
                     "as `radiance`)")
    fit.add_argument("--check-samples", type=_samples, default=4000, metavar="N",
                     help="Monte Carlo paths per value for --check montecarlo (default 4000)")
    fit.add_argument("--relative-uncertainty", type=float, default=None, metavar="FRACTION",
                     help="1-sigma uncertainty of the rows that give none, as a fraction of "
                     "their value (e.g. 0.03)")
    fit.add_argument("--model-error", type=float, default=None, metavar="FRACTION",
                     help="replace the forward model's stated error (docs/fit.md): a "
                     "fraction for radiance, absolute for chromaticity x, y")
    fit.add_argument("--model-error-correlation", type=float, default=0.0, metavar="RHO",
                     help="share (0-1) of the model error's variance common to all values "
                     "of one kind (default 0: independent; docs/fit.md)")
    fit.add_argument("--relative-weights", action="store_true",
                     help="the uncertainties are relative weights only: scale the covariance "
                     "by the reduced chi-square")
    fit.add_argument("--altitude", type=_number(checks.ALTITUDE_M), default=0.0, metavar="M",
                     help="the observer's altitude above the ground in metres (default 0)")
    image = fit.add_argument_group(
        "an image", "fit the luminance of --pixels sky pixels of a linear EXR of `render "
        "--exr` (rgb or luminance content), taken with the camera options below and the sun "
        "at --sun-zenith, --sun-azimuth (give --relative-uncertainty for its pixels)")
    image.add_argument("--image", type=Path, default=None, metavar="EXR",
                       help="the EXR image")
    image.add_argument("--sun-zenith", type=_number(checks.ZENITH_DEG), default=None,
                       metavar="DEG", help="the sun's zenith angle in the image, degrees")
    image.add_argument("--sun-azimuth", type=_number(checks.ANGLE_DEG), default=180.0,
                       metavar="DEG", help="the sun's azimuth from north towards east in the "
                       "image, degrees (default 180, as render)")
    image.add_argument("--pixels", type=int, default=200, metavar="N",
                       help="sky pixels to sample (default 200)")
    _add_camera_arguments(image, CAMERAS[:3], 512)
    fit.add_argument("-o", "--output", type=Path, default=None, metavar="REPORT.json",
                     help="write the report as JSON")
    fit.set_defaults(run=_fit)


def _fit(args: argparse.Namespace) -> None:
    from skyscatter import api
    if args.output is not None:
        check_writable_file(args.output)
    measurements = args.measurements
    if args.image is not None:
        if args.sun_zenith is None:
            raise InputError("--image needs the sun's place in it: give --sun-zenith DEG "
                             "(and --sun-azimuth)", key="sun_zenith")
        rows = api.image_measurements(args.image, _camera(args), args.sun_zenith,
                                      args.sun_azimuth, pixels=args.pixels)
        if measurements is not None:
            rows += api.measurement_rows(measurements)
        measurements = rows
    elif measurements is None:
        raise InputError("nothing to fit: give a MEASUREMENTS file or --image EXR",
                         key="measurements")
    result = api.fit(args.atmosphere, measurements, args.free, solver=args.solver,
                     model=args.model, refine=args.refine, checks=args.check,
                     relative_uncertainty=args.relative_uncertainty,
                     model_error=args.model_error,
                     model_error_correlation=args.model_error_correlation,
                     relative_weights=args.relative_weights,
                     altitude_m=args.altitude, samples=args.samples,
                     check_samples=args.check_samples)
    report = result.report
    for parameter in report["parameters"]:
        sigma = parameter["uncertainty"]
        shown = "unbounded" if sigma is None else f"{sigma:.4g}"
        print(f"{parameter['key']} = {parameter['estimate']:.6g} +- {shown} (1 sigma)"
              + ("" if parameter["constrained"] else "  NOT CONSTRAINED"))
    print(f"chi-square {report['chi_square']:.4g} for {report['degrees_of_freedom']} degrees "
          f"of freedom; {report['seconds']:.1f} s")
    for note in report["not_constrained"]:
        print(f"not constrained: {note['key']}: {note['reason']}")
    for check in report["checks"]:
        print(f"check {check['model']}: chi-square {check['chi_square_measurement_only']:.4g} "
              f"for {check['values']} values (measurement uncertainty only)")
    if args.output is not None:
        atomic_write(args.output, lambda path: Path(path).write_text(
            json.dumps(tidy(report), indent=1, allow_nan=False) + "\n", encoding="utf-8"))
        print(f"wrote {args.output}", file=sys.stderr)


def _rows_format(args: argparse.Namespace) -> str:
    """"csv", "json" or "netcdf" from --format and -o's suffix; InputError, before any work,
    for a suffix that contradicts --format, --metadata where it has no place, or an -o that
    cannot be written."""
    suffix = "" if args.output is None else args.output.suffix.lower()
    by_suffix = {".csv": "csv", ".json": "json", ".nc": "netcdf"}.get(suffix)
    place = args.metadata
    needs = {"envelope": "json", "comments": "csv"}.get(place)
    output_format = args.format or by_suffix or needs or "csv"
    if by_suffix is not None and by_suffix != output_format:
        raise InputError(f"-o {args.output} is {by_suffix}, but --format is {args.format}: name "
                         f"the file .{args.format} or leave --format out", key="output",
                         value=str(args.output))
    if output_format == "netcdf" and place is not None:
        raise InputError("a NetCDF file (.nc) carries the metadata as its attributes: leave "
                         "--metadata out", key="metadata", value=place)
    if needs is not None and output_format != needs:
        raise InputError(f"--metadata {place} is for {needs.upper()} output (--format "
                         f"{needs}); for {output_format.upper()} use "
                         f"{'comments' if needs == 'json' else 'envelope'} or sidecar",
                         key="metadata", value=place)
    if place == "sidecar" and args.output is None:
        raise InputError("--metadata sidecar writes FILE.meta.json beside -o FILE: give -o",
                         key="metadata", value=place)
    if args.output is not None:
        check_writable_file(args.output)
        if place == "sidecar":
            check_writable_file(sidecar_path(args.output))
    return output_format


def _rows_metadata(args: argparse.Namespace, atmosphere, rows: list[dict[str, float]],
                   options, sun_zeniths: list[float], geometry: dict, sky) -> dict | None:
    """The run's `api.output_metadata` when --metadata asks for it, else None; `sky`: the
    ephemeris of --time (`_sun_zeniths`), or None."""
    from skyscatter import api
    if args.metadata is None:
        return None
    place = {"altitude_m": args.altitude, "sun_zeniths_deg": sun_zeniths}
    if sky is not None:
        place.update(time=args.time, latitude_deg=args.lat, longitude_deg=args.lon,
                     sun_distance_m=sky.sun.distance_m)
    return api.output_metadata(atmosphere, list(rows[0]), args.wavelengths, solver=args.solver,
                               options=options, geometry={**place, **geometry})


def _write_rows(args: argparse.Namespace, output_format: str, rows: list[dict[str, float]],
                metadata: dict | None) -> None:
    """The rows to -o or standard output (`row_output`), the metadata where --metadata says."""
    inline = None if args.metadata == "sidecar" else metadata
    text = rows_json(rows, inline) if output_format == "json" else rows_csv(rows, inline)
    if args.output is None:
        sys.stdout.write(text)
        return
    with staged_outputs() as stage:
        stage.write(args.output, lambda path: Path(path).write_text(text, encoding="utf-8"))
        if args.metadata == "sidecar":
            stage.write(sidecar_path(args.output), lambda path: Path(path).write_text(
                metadata_json(metadata), encoding="utf-8"))


def _precompute(args: argparse.Namespace) -> None:
    import time

    from skyscatter import api
    atmosphere = api.load_atmosphere(args.atmosphere)
    if args.wavelengths is not None:
        parse = _wavelength_list(monochromatic=True) if args.monochromatic else _wavelengths
        try:
            args.wavelengths = parse(args.wavelengths)
        except argparse.ArgumentTypeError as error:
            raise InputError(f"--wavelengths: {error}", key="wavelengths",
                             value=args.wavelengths) from None
    start = time.perf_counter()
    with _solver_options(args, atmosphere) as options:
        tables = api.load_solver(atmosphere, args.wavelengths, solver="lut", options=options,
                                 monochromatic=args.monochromatic).tables
    print(f"{args.atmosphere}: {tables.orders} orders, {tables.wavelengths_nm.size} "
          f"wavelengths, {tables.nbytes / 2**20:.0f} MiB of tables, "
          f"{time.perf_counter() - start:.1f} s", file=sys.stderr)


def _add_export_tables_command(commands) -> None:
    """`skyscatter export-tables`: the tables, their sidecar and shaders for engines."""
    export = commands.add_parser(
        "export-tables", help="write the precomputed tables with a JSON sidecar and GLSL/HLSL "
        "code that reads them, for engines",
        description="Write the atmosphere's precomputed tables as textures for a game engine "
        "or renderer: transmittance and irradiance (2-D), scattering (3-D, the 4-D table "
        "packed as Bruneton's 2017 reference shaders pack it) and phase functions, a JSON "
        "sidecar (tables.json) with every constant a shader needs, and GLSL and HLSL that "
        "read them (the viewer's own shader code). The folder is replaced as a whole. "
        "docs/engines.md, \"Exported tables\", documents the layout.")
    _add_atmosphere_argument(export)
    export.add_argument("-o", "--output", type=Path, required=True, metavar="FOLDER",
                        help="the folder to write (made, or replaced if it holds only an "
                        "earlier export)")
    export.add_argument("--format", default="exr", metavar="FORMAT",
                        help="exr (one file per table; the 3-D table as a stack of slices), "
                        "ktx2 (KTX 2.0 textures, the 3-D table a 3-D texture) or npz "
                        "(default exr)")
    export.add_argument("--colour", default="rgb", metavar="CHANNELS",
                        help="rgb (linear --colour-space, 1.0 = 1 cd/m^2), xyz (CIE 1931) or "
                        "spectral (one channel per wavelength) (default rgb)")
    export.add_argument("--colour-space", default="srgb",
                        help="for --colour rgb: srgb (default), rec709, display-p3, rec2020, "
                        "acescg or aces2065-1")
    export.add_argument("--precision", default="half", metavar="half|float",
                        help="float16 (scaled per table, the scales in the sidecar) or "
                        "float32 (default half)")
    export.add_argument("--wavelengths", type=_wavelengths, default=None, metavar="N|LIST",
                        help="as for render: N bins over 360-830 nm or a list in nm (default "
                        f"{DEFAULT_WAVELENGTH_BINS} bins, the tables render uses)")
    export.add_argument("--orders", type=_orders, default=None,
                        help="scattering orders (default: the config's [tables] orders)")
    _add_cache_arguments(export)
    export.set_defaults(run=_export_tables)


def _export_tables(args: argparse.Namespace) -> None:
    import time

    from skyscatter import api
    atmosphere = api.load_atmosphere(args.atmosphere)
    start = time.perf_counter()
    with _solver_options(args, atmosphere) as options:
        exported = api.export_tables(atmosphere, args.output, args.format, args.colour,
                                     colour_space=args.colour_space, precision=args.precision,
                                     wavelengths_nm=args.wavelengths, options=options)
    size = sum(path.stat().st_size for path in exported.files)
    print(f"{args.atmosphere}: {len(exported.files)} files, {size / 2**20:.1f} MiB in "
          f"{exported.folder}, {time.perf_counter() - start:.1f} s", file=sys.stderr)


def _view(args: argparse.Namespace) -> None:
    from skyscatter import api

    def log(message: str) -> None:
        print(f"skyscatter: {message}", file=sys.stderr, flush=True)

    if args.clouds is not None:
        api.load_clouds(args.clouds)  # a bad file is named before the server starts
    server = api.viewer_server(args.atmosphere, host=args.host, port=args.port,
                               cache_dir=args.cache_dir, use_cache=not args.no_cache,
                               log=log if args.verbose else None)
    if args.clouds is not None:
        server.clouds.offer(args.clouds)
    if not api.is_loopback(args.host):
        print(f"skyscatter: WARNING: the viewer listens on {args.host}, not only on this "
              "computer: anyone on the network can reach it, over plain unencrypted HTTP.\n"
              "skyscatter: WARNING: only the secret token in the address below lets a page use "
              "it (and make this computer compute tables): share that address only with people "
              "you trust; --host 127.0.0.1 keeps the viewer to this computer.",
              file=sys.__stderr__ if args.quiet else sys.stderr, flush=True)  # --quiet too
    print(f"skyscatter viewer: {server.url}  (Ctrl-C stops it)", flush=True)
    api.serve_viewer(server, open_browser=not args.no_browser)


def _cache(args: argparse.Namespace) -> None:
    from skyscatter.checks import checked_number
    from skyscatter.disk_cache import TableCache
    if args.older_than is not None and args.action != "clear":
        raise InputError(f"--older-than applies to `skyscatter cache clear`, not to "
                         f"`{args.action}`", key="older_than", value=args.older_than)
    days = checked_number("--older-than", args.older_than or 0.0, low=0.0)
    cache = TableCache(args.cache_dir)
    if args.action == "clear":
        removed = cache.clear(older_than_s=days * 86400.0)
        freed = sum(entry.size_bytes for entry in removed)
        print(f"removed {len(removed)} entries ({freed / 2**20:.1f} MiB) from {cache.directory}")
        return
    entries = cache.entries()
    if args.action == "size":
        total = sum(entry.size_bytes for entry in entries)
        print(f"{total / 2**20:.1f} MiB in {len(entries)} entries in {cache.directory} "
              f"(limit {cache.max_bytes / 2**20:.0f} MiB)")
        return
    rows = [entry.summary(cache.directory) for entry in entries]
    if args.format == "json":
        json.dump({"directory": str(cache.directory), "max_bytes": cache.max_bytes,
                   "entries": rows}, sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
        return
    for row in rows:
        what = row["what"]
        if "constituents" in row:
            what += " of " + "+".join(row["constituents"])
        if "orders" in row:
            what += f", {row['orders']} orders"
        if "wavelengths_nm" in row:
            w = row["wavelengths_nm"]
            what += f", {w['count']} wavelengths {w['first']:g}-{w['last']:g} nm"
        name = row["key"] if row["folder"] == "." else f"{row['folder']}/{row['key']}"
        print(f"{name}  {row['size_bytes'] / 2**20:8.1f} MiB  {row['last_used']}  {what}")


def _validate(args: argparse.Namespace) -> int:
    from skyscatter import api
    from skyscatter.disk_cache import TableCache
    from skyscatter.output_files import check_writable_file

    if args.output.exists() and not args.output.is_dir():
        raise InputError(f"--output {args.output} is a file; give a directory",
                         key="output", value=str(args.output))
    check_writable_file(args.output / "report.md")  # before the suite, not after it

    def log(message: str) -> None:
        print(f"skyscatter: {message}", file=sys.stderr, flush=True)

    def on_case(result) -> None:
        state = "passed" if result.passed else "FAILED"
        if not result.checks:
            state = "reported"
        print(f"{result.key}: {state}, {sum(c.passed for c in result.checks)}/"
              f"{len(result.checks)} checks within limits, {result.seconds:.0f} s", flush=True)
        for check in result.checks:
            if not check.passed:
                print(f"  FAILED {check.name}: {check.value:.3g}{check.unit} > "
                      f"{check.limit:.3g}{check.unit}", flush=True)

    settings = api.ValidationSettings(args.output, quick=args.quick,
                                  cache=None if args.no_cache else TableCache(args.cache_dir),
                                  log=log, seed=args.seed)
    try:
        outcome = api.run_validation(settings, args.cases, on_case, scheduler=args.scheduler,
                                     workers=args.workers)
    except OSError as error:
        raise InputError(f"cannot write the report into {args.output}: {error.strerror}",
                         key="output", value=str(args.output)) from None
    print(f"{'PASSED' if outcome.passed else 'FAILED'} in {outcome.seconds:.0f} s; report: "
          f"{outcome.report_path}, summary: {outcome.summary_path}")
    return 0 if outcome.passed else 3


# the commands whose first run compiles kernels (`compile_ahead`)
COMPILING_COMMANDS = frozenset({"render", "timelapse", "radiance", "irradiance", "precompute",
                                "view", "validate", "export-tables", "compare"})


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `skyscatter` command; returns the exit code."""
    from skyscatter.errors import SkyscatterError
    from skyscatter.output_files import Terminated, sigterm_as_interrupt

    parser = build_parser()
    if not (sys.argv[1:] if argv is None else argv):
        parser.print_help()  # `skyscatter` alone: what it can do
        return 0
    parser.argv = list(sys.argv[1:] if argv is None else argv)  # for `_did_you_mean`
    args = _parse(parser, parser.argv)
    args.command_line = parser.argv
    first_run = False
    if args.command in COMPILING_COMMANDS:
        from skyscatter import compile_ahead
        first_run = not compile_ahead.kernels_compiled()
        if first_run and not args.quiet:
            print(compile_ahead.FIRST_RUN_NOTE, file=sys.stderr, flush=True)
    try:
        # SIGTERM cleans up like Ctrl-C
        with sigterm_as_interrupt(), _stderr_unless_quiet(args.quiet):
            code = args.run(args)
    except SkyscatterError as error:
        if args.debug:
            raise
        print(f"skyscatter: {error}", file=sys.stderr)
        return 2
    except Terminated:
        print("skyscatter: terminated", file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print("skyscatter: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `skyscatter radiance ... | head`: the reader left
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - stops the flush at exit failing
        return 0
    except Exception as error:  # our bug: say so, briefly
        if args.debug:
            raise
        print(f"skyscatter: internal error: {type(error).__name__}: {error} "
              "(run with --debug for the traceback and please report it)", file=sys.stderr)
        return 1
    if first_run and not code:
        compile_ahead.mark_compiled()
    return code or 0


if __name__ == "__main__":
    sys.exit(main())
