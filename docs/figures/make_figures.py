"""Make every picture in the docs (docs/images/*.png) with the command line; run from the
repo root: python docs/figures/make_figures.py

README pictures, and for docs/physics/tables.md the same sunset panorama with single scattering
(ray marched) and with the precomputed tables. The albedo map of the views from space is made
here too: procedural continents (docs/images/demo_albedo.png), since no Earth map ships."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from skyscatter.cli import main
from skyscatter.render.image_io import write_png
from skyscatter.spectrum.colour import encode_srgb_transfer

IMAGES = Path(__file__).resolve().parents[1] / "images"
ALBEDO_MAP = IMAGES / "demo_albedo.png"
TABLES_SCENE = ["earth", "--sun-elevation", "4", "--sun-azimuth", "270", "--camera",
                "panorama", "--heading", "270", "--size", "160", "--exposure", "12"]
# Looking west at the setting sun like the InSight and Spirit cameras; a fixed exposure and the
# Reinhard curve keep the bright aureole from clipping to white, so its blue shows.
MARS_SUNSET = ["--sun-elevation", "2", "--sun-azimuth", "270", "--camera", "perspective",
               "--heading", "270", "--pitch", "20", "--fov", "70", "--size", "320",
               "--exposure", "16", "--tonemap", "reinhard"]
EXO_SUNSET = ["--sun-elevation", "3", "--sun-azimuth", "270", "--camera", "perspective",
              "--heading", "270", "--pitch", "20", "--fov", "80", "--size", "320"]
FIGURES = {
    "earth_noon.png": ["earth", "--sun-elevation", "60", "--size", "256"],
    "earth_sunset.png": ["earth", "--sun-elevation", "2", "--sun-azimuth", "270", "--size",
                         "256"],
    "earth_sunset_panorama.png": ["earth", "--sun-elevation", "2", "--sun-azimuth", "270",
                                  "--camera", "panorama", "--heading", "270", "--size", "192"],
    "mars_afternoon.png": ["mars-costa", "--sun-elevation", "35", "--sun-azimuth", "240",
                           "--size", "256"],
    "earth_from_space.png": ["earth", "--camera", "orbit", "--distance-km", "20000", "--lat",
                             "30", "--sun-elevation", "15", "--sun-azimuth", "90", "--size",
                             "256"],
    "earth_mountains.png": ["earth", "--sun-elevation", "12", "--sun-azimuth", "235",
                            "--camera", "perspective", "--heading", "180", "--pitch", "3",
                            "--fov", "50", "--size", "270", "--altitude", "300", "--terrain",
                            "demo"],
    "earth_from_space_map.png": ["earth", "--camera", "orbit", "--distance-km", "12000",
                                 "--lat", "15", "--lon", "20", "--sun-elevation", "25",
                                 "--sun-azimuth", "260", "--size", "320", "--albedo-map",
                                 str(ALBEDO_MAP)],
    "earth_terminator.png": ["earth", "--camera", "orbit", "--distance-km", "800", "--lat",
                             "0", "--sun-elevation", "-4", "--sun-azimuth", "90", "--size",
                             "270", "--look-at", "0,25", "--fov", "70",
                             "--albedo-map", str(ALBEDO_MAP)],
    "mars_noon.png": ["mars-physical", "--sun-elevation", "60", "--sun-azimuth", "180",
                      "--size", "256"],
    "mars_sunset_glow.png": ["mars-physical", *MARS_SUNSET],
    "mars_from_orbit.png": ["mars-physical", "--camera", "orbit", "--distance-km", "7000",
                            "--lat", "10", "--sun-elevation", "10", "--sun-azimuth", "90",
                            "--size", "320"],
    **{f"mars_sunset_{model}.png": [f"mars-{model}", *MARS_SUNSET, "--size", "200"]
       for model in ("collienne", "costa", "bluemoon", "hybrid")},
    "exo_hazy_noon.png": ["exo-hazy", "--sun-elevation", "45", "--sun-azimuth", "180",
                          "--size", "256"],
    "exo_hazy_sunset.png": ["exo-hazy", *EXO_SUNSET],
    "exo_dense_n2_noon.png": ["exo-dense-n2", "--sun-elevation", "45", "--sun-azimuth", "180",
                              "--size", "256"],
    "exo_dense_n2_sunset.png": ["exo-dense-n2", *EXO_SUNSET],
    "tables_sunset_single.png": [*TABLES_SCENE, "--solver", "single"],
    "tables_sunset_lut.png": [*TABLES_SCENE, "--solver", "lut"],
}



def make_mars_phase_figure(path: Path) -> None:
    """The dust phase functions of the four Meyran 2022 Mars models at 440 and 680 nm (as the
    thesis's Fig. 4.2/4.4), plus the scattering-weighted Mie average for comparison."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skyscatter.atmosphere.config import load_atmosphere
    from skyscatter.optics.mie import MieOptics, particle_optics
    from skyscatter.optics.particle_index import ComplexIndex, load_material, maxwell_garnett
    from skyscatter.optics.size_distribution import ModifiedGamma

    theta = np.linspace(0.0, 180.0, 1801)
    nu = np.cos(np.radians(theta))
    wavelengths = np.array([440.0, 680.0])
    curves = {}
    for name in ("mars-collienne", "mars-costa", "mars-bluemoon", "mars-hybrid"):
        dust = next(c for c in load_atmosphere(name).constituents if c.name == "dust")
        curves[name] = dust.optics.phase.evaluate(nu, wavelengths)
    index = maxwell_garnett(ComplexIndex.constant(1.5), load_material("hematite"), 0.03)
    weighted = MieOptics(particle_optics(ModifiedGamma(1.6e-6, 0.2), index, wavelengths))
    curves["Mie, C_sca-weighted"] = weighted.phase.evaluate(nu, wavelengths)
    figure, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), sharey=True)
    for k, (axis, wavelength) in enumerate(zip(axes, wavelengths, strict=True)):
        for label, values in curves.items():
            axis.plot(theta, values[:, k], label=label,
                      ls=":" if label.startswith("Mie") else "-")
        axis.set_yscale("log")
        axis.set_xlabel("scattering angle [deg]")
        axis.set_title(f"{wavelength:g} nm", fontsize=10)
        axis.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("phase function [sr^-1]")
    axes[0].legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def make_albedo_map(path: Path, width: int = 1024, seed: int = 4) -> None:
    """Procedural continents on an equirectangular map: smooth noise (Gaussian-filtered in
    Fourier space) thresholded to 30 % land; deep blue sea, green and desert land by latitude,
    ice caps. Linear reflectances, written sRGB-encoded."""
    height = width // 2
    rng = np.random.default_rng(seed)
    ky = np.fft.fftfreq(height)[:, None]
    kx = np.fft.fftfreq(width)[None, :]
    field = np.fft.ifft2(np.fft.fft2(rng.normal(size=(height, width)))
                         * np.exp(-(kx**2 + ky**2) / (2 * 0.012**2))).real
    latitude = np.linspace(90.0, -90.0, height)[:, None] * np.ones((1, width))
    land = field > np.quantile(field, 0.70)
    dry = np.clip(1.0 - np.abs(np.abs(latitude) - 25.0) / 15.0, 0.0, 1.0)
    ground = ((1.0 - dry)[..., None] * np.array([0.07, 0.11, 0.05])
              + dry[..., None] * np.array([0.36, 0.28, 0.17]))
    rgb = np.where(land[..., None], ground, np.array([0.015, 0.03, 0.07]))
    ice = np.abs(latitude) > 72.0 - 4.0 * np.tanh(field / field.std())
    rgb[ice] = [0.75, 0.78, 0.82]
    write_png(path, np.round(255.0 * encode_srgb_transfer(rgb)).astype(np.uint8))


if __name__ == "__main__":
    make_albedo_map(ALBEDO_MAP)
    make_mars_phase_figure(IMAGES / "mars_dust_phase.png")
    for name, arguments in FIGURES.items():
        argv = ["render", *arguments, "-o", str(IMAGES / name)]
        print("skyscatter " + " ".join(argv))
        if main(argv) != 0:
            sys.exit(1)
