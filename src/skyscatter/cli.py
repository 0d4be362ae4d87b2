"""Command line: `skyscatter render | radiance | presets`. Thin: parse, call `api`, print.

User errors (`SkyscatterError`) print one line and exit with code 2; anything else is our bug
and exits with 1 (the traceback only with --debug). Progress bars appear only on a terminal.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from skyscatter import __version__

__all__ = ["main"]

CAMERAS = ("fisheye", "panorama", "perspective", "orbit")


def _float_list(text: str) -> list[float]:
    """'0,30,60' -> [0.0, 30.0, 60.0] (argparse type)."""
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a comma-separated list of numbers (e.g. 0,30,60)") from None
    if not values:
        raise argparse.ArgumentTypeError("the list is empty; give numbers like 0,30,60")
    return values


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{value} must be > 0")
    return value


def _exposure(text: str) -> float | None:
    if text == "auto":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is neither 'auto' nor an EV100 number") from None


def _wavelengths(text: str) -> list[float]:
    """'16' -> a 16-bin grid over 360-830 nm; '440,550,680' -> those wavelengths."""
    if "," not in text:
        count = _positive_int(text)
        from skyscatter.spectrum.grid import wavelength_grid
        return list(wavelength_grid(count))
    return _float_list(text)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="skyscatter", description="Physically based skies of Earth, Mars and other "
        "planets: spectral radiance and images from atmosphere descriptions (TOML).")
    parser.add_argument("--version", action="version", version=f"skyscatter {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    presets = commands.add_parser("presets", help="list the shipped atmosphere presets",
                                  description="List the shipped presets with a one-line "
                                  "description each.")
    presets.set_defaults(run=_presets)

    render = commands.add_parser(
        "render", help="render a sky image (PNG and/or EXR)",
        description="Render the sky seen from the ground or the air to a tone-mapped PNG and "
        "optionally a linear EXR in physical units. Example: skyscatter render earth "
        "--sun-elevation 5 --camera panorama -o sunset.png --exr sunset.exr")
    render.add_argument("atmosphere", metavar="PRESET_OR_CONFIG",
                        help="a preset name (see `skyscatter presets`) or a TOML file")
    sun = render.add_mutually_exclusive_group()
    sun.add_argument("--sun-zenith", type=float, metavar="DEG",
                     help="sun zenith angle in degrees (0 = overhead)")
    sun.add_argument("--sun-elevation", type=float, metavar="DEG",
                     help="sun elevation above the horizon in degrees (default 30)")
    render.add_argument("--sun-azimuth", type=float, default=180.0, metavar="DEG",
                        help="sun azimuth from north towards east in degrees (default 180)")
    render.add_argument("--camera", choices=CAMERAS, default="fisheye",
                        help="fisheye: all-sky, zenith at centre, north up, east left; "
                        "panorama: equirectangular 2:1; perspective: pinhole; orbit: the planet "
                        "from space, looking at its centre from --distance-km above "
                        "--lat/--lon, north up (default fisheye)")
    render.add_argument("--size", type=_positive_int, default=512, metavar="PIXELS",
                        help="image height in pixels (panorama width = 2 x size; "
                        "perspective width from --aspect) (default 512)")
    render.add_argument("--aspect", type=float, default=16 / 9,
                        help="perspective width / height (default 16/9)")
    render.add_argument("--fov", type=float, default=None, metavar="DEG",
                        help="vertical field of view in degrees (default 60 for perspective; "
                        "orbit: the whole planet)")
    render.add_argument("--distance-km", type=float, default=None, metavar="KM",
                        help="orbit camera: height above the ground in km (default: the "
                        "planet's radius)")
    render.add_argument("--lat", type=float, default=0.0, metavar="DEG",
                        help="orbit camera: latitude below the camera in degrees (default 0)")
    render.add_argument("--lon", type=float, default=0.0, metavar="DEG",
                        help="orbit camera: longitude below the camera in degrees (default 0)")
    render.add_argument("--heading", type=float, default=180.0, metavar="DEG",
                        help="view azimuth from north towards east for perspective and "
                        "panorama centre, degrees (default 180: south)")
    render.add_argument("--pitch", type=float, default=10.0, metavar="DEG",
                        help="perspective view elevation in degrees (default 10)")
    render.add_argument("--altitude", type=float, default=0.0, metavar="M",
                        help="observer altitude above the ground in metres (default 0)")
    render.add_argument("--wavelengths", type=_wavelengths, default=None, metavar="N|LIST",
                        help="N bins over 360-830 nm, or a comma-separated list in nm "
                        "(default 16 bins)")
    render.add_argument("--samples", type=_positive_int, default=64,
                        help="ray-marching samples per view ray (default 64)")
    render.add_argument("--solver", default="single", help="solver name (default single)")
    render.add_argument("--exposure", type=_exposure, default=None, metavar="EV100|auto",
                        help="exposure value EV100, or auto (default auto)")
    render.add_argument("--exposure-compensation", type=float, default=1.0, metavar="EV",
                        help="brightens the metered exposure by this many stops (default +1: "
                        "a clear sky metered to middle grey looks a stop too dark)")
    render.add_argument("--tonemap", default="aces",
                        help="aces (filmic, default), exponential (Costa/Bruneton), "
                        "reinhard or clamp")
    render.add_argument("--colour-space", default="srgb",
                        help="srgb (default), display-p3, rec2020 or acescg")
    render.add_argument("--white-balance", choices=("none", "star"), default="none",
                        help="none, or adapt the star's white (its top-of-atmosphere "
                        "spectrum) to D65 (default none)")
    render.add_argument("-o", "--output", type=Path, default=Path("sky.png"),
                        help="PNG path (default sky.png)")
    render.add_argument("--exr", type=Path, default=None, help="also write a linear EXR")
    render.add_argument("--exr-content", choices=("rgb", "luminance", "spectral"),
                        default="rgb", help="what the EXR holds (default rgb)")
    render.set_defaults(run=_render)

    radiance = commands.add_parser(
        "radiance", help="print spectral sky radiance as CSV or JSON",
        description="Print diffuse spectral sky radiance [W m^-2 sr^-1 nm^-1] (the sun disk "
        "itself not included) for every combination of the lists. View zenith 0 looks straight "
        "up; relative azimuth 0 looks towards the sun.")
    radiance.add_argument("atmosphere", metavar="PRESET_OR_CONFIG",
                          help="a preset name (see `skyscatter presets`) or a TOML file")
    radiance.add_argument("--sun-zenith", type=_float_list, required=True, metavar="DEG,...",
                          help="sun zenith angles in degrees")
    radiance.add_argument("--view-zenith", type=_float_list, default=[0.0], metavar="DEG,...",
                          help="view zenith angles in degrees (default 0)")
    radiance.add_argument("--view-azimuth", type=_float_list, default=[0.0],
                          metavar="DEG,...", help="view azimuths relative to the sun in "
                          "degrees (default 0)")
    radiance.add_argument("--wavelengths", type=_float_list, default=[440.0, 550.0, 680.0],
                          metavar="NM,...", help="wavelengths in nm (default 440,550,680)")
    radiance.add_argument("--altitude", type=float, default=0.0, metavar="M",
                          help="observer altitude in metres (default 0)")
    radiance.add_argument("--solver", default="single", help="solver name (default single)")
    radiance.add_argument("--samples", type=_positive_int, default=512,
                          help="ray-marching samples per view ray (default 512)")
    radiance.add_argument("--format", choices=("csv", "json"), default="csv",
                          help="output format (default csv)")
    radiance.set_defaults(run=_radiance)
    return parser


def _presets(args: argparse.Namespace) -> None:
    from skyscatter.api import list_presets
    presets = list_presets()
    width = max(len(name) for name in presets)
    for name, description in presets.items():
        print(f"{name:<{width}}  {description}")


def _render(args: argparse.Namespace) -> None:
    from skyscatter import api
    from skyscatter.errors import InputError
    from skyscatter.render.progress import progress

    atmosphere = api.load_atmosphere(args.atmosphere)
    zenith = (args.sun_zenith if args.sun_zenith is not None
              else 90.0 - (30.0 if args.sun_elevation is None else args.sun_elevation))
    orbit = args.camera == "orbit"
    altitude = args.altitude
    if orbit:
        radius = atmosphere.planet.radius_m
        altitude = radius if args.distance_km is None else args.distance_km * 1000.0
        if not altitude > 0.0:
            raise InputError(f"--distance-km {args.distance_km} must be > 0", key="distance_km",
                             value=args.distance_km)
        fov = args.fov if args.fov is not None else api.orbit_field_of_view_deg(altitude,
                                                                                radius)
        camera = api.PerspectiveCamera(args.size, args.size, fov, heading_deg=0.0,
                                       pitch_deg=-90.0)
    else:
        camera = _camera(args)
    directions, valid = camera.directions()
    with progress(int(valid.sum()), "rendering", unit="ray") as bar:
        image = api.render(atmosphere, camera, zenith, args.sun_azimuth, altitude,
                           args.wavelengths, args.solver, args.samples, bar.update,
                           orbit_latitude_deg=args.lat if orbit else None,
                           orbit_longitude_deg=args.lon)
    ev100 = api.save_image(image, args.output, args.exr, args.exposure,
                           args.exposure_compensation, args.tonemap, args.colour_space,
                           args.white_balance == "star", args.exr_content)
    written = [str(args.output)] + ([str(args.exr)] if args.exr else [])
    print(f"wrote {', '.join(written)} (EV100 {ev100:.2f})", file=sys.stderr)


def _camera(args: argparse.Namespace):
    from skyscatter import api
    if args.camera == "fisheye":
        return api.FisheyeCamera(args.size)
    if args.camera == "panorama":
        return api.EquirectangularCamera(2 * args.size, args.size, heading_deg=args.heading)
    width = max(1, round(args.size * args.aspect))
    fov = 60.0 if args.fov is None else args.fov
    return api.PerspectiveCamera(width, args.size, fov, heading_deg=args.heading,
                                 pitch_deg=args.pitch)


def _radiance(args: argparse.Namespace) -> None:
    from skyscatter import api
    atmosphere = api.load_atmosphere(args.atmosphere)
    rows = api.sky_radiance_rows(atmosphere, args.sun_zenith, args.view_zenith,
                                 args.view_azimuth, args.wavelengths, args.altitude,
                                 args.solver, args.samples)
    if args.format == "json":
        json.dump(rows, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        writer = csv.DictWriter(sys.stdout, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows({key: f"{value:.10g}" for key, value in row.items()} for row in rows)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `skyscatter` command; returns the exit code."""
    from skyscatter.errors import SkyscatterError

    args = build_parser().parse_args(argv)
    try:
        args.run(args)
    except SkyscatterError as error:
        if args.debug:
            raise
        print(f"skyscatter: {error}", file=sys.stderr)
        return 2
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
