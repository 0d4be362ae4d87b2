"""Make the pictures of docs/sky_at_a_date.md (skies at a date: sun, moon, stars, eclipses,
time-lapses); run from the repo root: python docs/figures/make_sky_figures.py

Narrow views are aimed at the moon or the sun with the position the ephemeris gives; montages
are put together with Pillow."""

from __future__ import annotations

import datetime
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from skyscatter import api
from skyscatter.astro.earth_sky import refract
from skyscatter.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "images"
BERLIN = ("52.52", "13.40")
FIGURES = {
    "sky_berlin_2130.png": ["earth", "--time", "2024-06-21T21:30+02:00", "--lat", BERLIN[0],
                            "--lon", BERLIN[1], "--camera", "panorama", "--heading", "315",
                            "--size", "200"],
    "sky_full_moon_night.png": ["earth", "--time", "2024-01-25T23:00+01:00", "--lat",
                                BERLIN[0], "--lon", BERLIN[1], "--size", "384"],
    "sky_milky_way.png": ["earth", "--time", "2024-07-05T02:00-04:00", "--lat", "-29.26",
                          "--lon", "-70.73", "--milky-way", "--size", "512"],
}
MOON_PHASES = [("waxing crescent", "2024-01-14T16:30Z"), ("first quarter", "2024-01-18T17:00Z"),
               ("waxing gibbous", "2024-01-22T20:00Z"), ("full", "2024-01-25T22:00Z")]
# Fixed exposures, as a photographer would set them: the sunlit moon (about 3000 cd m^-2 at
# full moon) and the eclipsed one, 10 magnitudes fainter at mid-totality.
MOON_EXPOSURE = ["--exposure", "13.5", "--tonemap", "reinhard"]
ECLIPSE_EXPOSURES = {"2022-11-08T08:45Z": "13.5", "2022-11-08T09:40Z": "13.5",
                     "2022-11-08T10:59Z": "2"}


def aim(atmosphere, time: str, latitude: float, longitude: float, body: str) -> list[str]:
    """--heading/--pitch of a perspective camera aimed at the refracted sun or moon."""
    sky = api.sky_ephemeris(atmosphere, api.make_observer(time, latitude, longitude))
    position = sky.moon if body == "moon" else sky.sun
    seen = refract(position.direction())
    azimuth = float(np.degrees(np.arctan2(seen[0], seen[1]))) % 360.0
    altitude = float(np.degrees(np.arcsin(seen[2])))
    return ["--camera", "perspective", "--heading", f"{azimuth:.4f}", "--pitch",
            f"{altitude:.4f}"]


def render(name: str, arguments: list[str], folder: Path = IMAGES) -> Path:
    path = folder / name
    argv = ["render", *arguments, "-o", str(path)]
    print("skyscatter " + " ".join(argv), flush=True)
    if main(argv) != 0:
        sys.exit(1)
    return path


def montage(paths: list[Path], target: Path) -> None:
    images = [Image.open(p).convert("RGB") for p in paths]
    width, height = images[0].size
    sheet = Image.new("RGB", (width * len(images), height))
    for index, image in enumerate(images):
        sheet.paste(image, (index * width, 0))
    sheet.save(target)


def make_moon_figures(folder: Path) -> None:
    earth = api.load_atmosphere("earth")
    phases = []
    for label, time in MOON_PHASES:
        name = f"moon_{label.replace(' ', '_')}.png"
        phases.append(render(name, ["earth", "--time", time, "--lat", BERLIN[0], "--lon",
                                    BERLIN[1], *aim(earth, time, 52.52, 13.40, "moon"), "--fov",
                                    "0.8", "--size", "160", "--aspect", "1", "--no-stars",
                                    *MOON_EXPOSURE], folder))
    montage(phases, IMAGES / "moon_phases.png")
    eclipse = []
    for time, ev100 in ECLIPSE_EXPOSURES.items():
        eclipse.append(render(f"eclipse_{time[-6:-1].replace(':', '')}.png", [
            "earth", "--time", time, "--lat", "21.31", "--lon", "-157.86",
            *aim(earth, time, 21.31, -157.86, "moon"), "--fov", "0.8", "--size", "160",
            "--aspect", "1", "--no-stars", "--exposure", ev100, "--tonemap", "reinhard"],
            folder))
    montage(eclipse, IMAGES / "lunar_eclipse_2022.png")


def make_sun_sizes(folder: Path) -> None:
    """The sun's disk from Earth (Berlin, June noon) and from Mars (Gale crater, a high sun),
    same 2° field of view and fixed exposure."""
    earth, mars = api.load_atmosphere("earth"), api.load_atmosphere("mars-physical")
    earth_time = "2024-06-21T12:00+02:00"
    start = datetime.datetime(2024, 6, 21, tzinfo=datetime.UTC)
    mars_time = max((start + datetime.timedelta(minutes=20 * i) for i in range(80)),
                    key=lambda t: api.sky_ephemeris(mars, api.make_observer(
                        t, -4.59, 137.44)).sun.altitude_deg).isoformat()
    common = ["--fov", "2", "--size", "160", "--aspect", "1", "--no-stars", "--exposure", "17",
              "--tonemap", "reinhard"]
    paths = [render("sun_from_earth.png", ["earth", "--time", earth_time, "--lat", BERLIN[0],
                                            "--lon", BERLIN[1],
                                            *aim(earth, earth_time, 52.52, 13.40, "sun"),
                                            *common], folder),
             render("sun_from_mars.png", ["mars-physical", "--time", mars_time, "--lat",
                                          "-4.59", "--lon", "137.44",
                                          *aim(mars, mars_time, -4.59, 137.44, "sun"), *common],
                    folder)]
    montage(paths, IMAGES / "sun_earth_mars.png")


def make_physics_plots() -> None:
    """docs/physics/moon.md: our lunar phase curve against Allen's; docs/physics/tables.md:
    the zenith sky through twilight against the airglow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skyscatter.render import moon
    from skyscatter.render.airglow import airglow_radiance
    from skyscatter.spectrum.colour import spectral_to_xyz
    from skyscatter.spectrum.grid import wavelength_grid
    from skyscatter.spectrum.magnitudes import v_magnitude_of_spectrum
    from skyscatter.spectrum.star import Star

    wavelengths = wavelength_grid(64)
    sunlight = Star.sun().irradiance_toa(wavelengths)
    angles = np.linspace(2.0, 150.0, 75)
    ours = [float(v_magnitude_of_spectrum(wavelengths, moon.moon_irradiance(
        moon._phase_geometry(a, True), wavelengths, sunlight, earthshine=False)))
        for a in angles]
    figure, axis = plt.subplots(figsize=(6, 3.6))
    axis.plot(angles, moon.allen_phase_curve_v(angles), "k--", label="Allen (Cox 2000)")
    axis.plot(angles, ours, label="skyscatter (Hapke-Lommel-Seeliger, maria)")
    axis.invert_yaxis()
    axis.set(xlabel="phase angle [deg]", ylabel="V magnitude at 384 400 km",
             title="The moon's brightness with its phase")
    axis.legend()
    figure.tight_layout()
    figure.savefig(IMAGES / "moon_phase_curve.png", dpi=110)
    plt.close(figure)

    earth = api.load_atmosphere("earth")
    solver = api.load_solver(earth)
    grid = solver.profile.wavelengths_nm
    position = np.array([0.0, 0.0, solver.profile.bottom_radius_m + 1.0])
    zeniths = np.arange(80.0, 112.1, 0.5)
    views = {"zenith": api.sun_direction(0.0, 0.0),
             "60 deg towards the sun": api.sun_direction(60.0, 0.0),
             "60 deg away from the sun": api.sun_direction(60.0, 180.0)}
    figure, axis = plt.subplots(figsize=(6, 3.8))
    for label, view in views.items():
        luminance = [spectral_to_xyz(solver.sky_radiance(position, view[None],
                                                         api.sun_direction(z, 0.0))[0],
                                     grid)[1] for z in zeniths]
        axis.semilogy(zeniths, luminance, label=label)
    glow = spectral_to_xyz(airglow_radiance(np.array([1.0]), grid, position[2],
                                            solver.profile.bottom_radius_m)[0], grid)[1]
    axis.axhline(glow, color="g", ls=":", label="airglow at the zenith")
    for edge in (96.0, 102.0, 108.0):
        axis.axvline(edge, color="0.6", lw=0.8)
    axis.set(xlabel="sun zenith angle [deg]\n(grey: civil, nautical, astronomical twilight end)",
             ylabel="luminance [cd m$^{-2}$]", ylim=(1e-8, 1e4),
             title="Sky luminance through twilight (earth preset, tables)")
    axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(IMAGES / "twilight_luminance.png", dpi=110)
    plt.close(figure)


def make_solar_eclipse(folder: Path) -> None:
    """The partial phases of the 2024-04-08 eclipse from Dallas, a 1.5° view on the sun, fixed
    exposure."""
    earth = api.load_atmosphere("earth")
    paths = []
    for time in ("2024-04-08T17:45Z", "2024-04-08T18:15Z", "2024-04-08T18:38Z"):
        paths.append(render(f"solar_{time[11:16].replace(':', '')}.png", [
            "earth", "--time", time, "--lat", "32.7767", "--lon", "-96.7970",
            *aim(earth, time, 32.7767, -96.7970, "sun"), "--fov", "1.5", "--size", "160",
            "--aspect", "1", "--no-stars", "--exposure", "17", "--tonemap", "reinhard"],
            folder))
    montage(paths, IMAGES / "solar_eclipse_2024.png")


def make_timelapse(folder: Path) -> None:
    video = IMAGES / "timelapse_berlin.gif"
    frames = folder / "timelapse_frames"
    argv = ["timelapse", "earth", "--start", "2024-06-21T20:30+02:00", "--end",
            "2024-06-22T00:30+02:00", "--step", "8min", "--lat", BERLIN[0], "--lon", BERLIN[1],
            "--size", "160", "--fps", "8", "--twinkle", "1", "-o", str(video), "--frames-dir",
            str(frames)]
    print("skyscatter " + " ".join(argv), flush=True)
    if main(argv) != 0:
        sys.exit(1)
    picked = sorted(frames.glob("frame_*.png"))[::5][:8]
    montage(picked, IMAGES / "timelapse_berlin_sheet.png")


if __name__ == "__main__":
    for figure, arguments in FIGURES.items():
        render(figure, arguments)
    make_physics_plots()
    with tempfile.TemporaryDirectory() as scratch:
        make_moon_figures(Path(scratch))
        make_sun_sizes(Path(scratch))
        make_solar_eclipse(Path(scratch))
        make_timelapse(Path(scratch))
