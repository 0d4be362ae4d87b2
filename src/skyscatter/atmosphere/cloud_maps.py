"""Coverage maps of cloud layers over a whole planet, and a demo map of Earth's cloud cover.

A coverage map is equirectangular: column 0 starts at longitude -180 deg, row 0 at latitude
+90 deg (the layout of `render.albedo_map`), values 0-1: the factor a layer's `coverage`
is multiplied by at each planetocentric latitude and longitude
(`atmosphere._cloud_sampling.coverage_map_factor`). `read_coverage_map` reads one from an
8- or 16-bit grey PNG (values / 255 or / 65535, no sRGB decoding: the grey levels are
fractions) or a float .npy array.

`demo_coverage_map` makes Earth-like weather for the `earth-weather` cloud preset: the
zonal-mean annual cloud fraction of `zonal_cloud_fraction` (the intertropical convergence
zone, the dry subtropics, the storm tracks) times large-scale noise on the sphere (Perlin
gradient noise of `atmosphere.cloud_noise`, warped so that it swirls). The shipped
`cloud_presets/earth-weather-coverage.png` is its output
(`python scripts/make_data/cloud_coverage_map.py`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skyscatter.errors import InputError, read_user_file

__all__ = [
    "MAX_MAP_PIXELS",
    "ZONAL_CLOUD_FRACTION",
    "demo_coverage_map",
    "read_coverage_map",
    "write_coverage_png",
    "zonal_cloud_fraction",
]

MAX_MAP_PIXELS = 4096 * 2048  # 64 MiB as float64 per layer: finer than any cloud climatology

# Zonal-mean annual total cloud fraction [0-1] at latitudes [deg]: read (to about +-0.05)
# from the zonal means of the GEWEX Cloud Assessment (Stubenrauch et al. 2013, Bull. Amer.
# Meteor. Soc. 94, 1031, doi:10.1175/BAMS-D-12-00117.1, Fig. 3: CALIPSO and ISCCP total cloud
# amount, global mean 0.68 +- 0.03) and MODIS (King et al. 2013, IEEE Trans. Geosci. Remote
# Sens. 51, 3826, doi:10.1109/TGRS.2012.2227333, zonal cloud fraction): the Southern Ocean
# storm track near 60 S (~0.85-0.9), the subtropical minima near 20-30 N/S (0.5-0.6; the
# Sahara far below), the ITCZ near 5-10 N (~0.7), the northern storm tracks (~0.75-0.8);
# polar values are the least certain (passive sensors over ice).
ZONAL_CLOUD_FRACTION = np.array([
    (-90.0, 0.55), (-75.0, 0.65), (-60.0, 0.88), (-45.0, 0.80), (-30.0, 0.60), (-18.0, 0.55),
    (-5.0, 0.62), (7.0, 0.72), (20.0, 0.52), (30.0, 0.55), (45.0, 0.72), (60.0, 0.80),
    (75.0, 0.75), (90.0, 0.70)])


def zonal_cloud_fraction(latitude_deg: np.ndarray) -> np.ndarray:
    """Zonal-mean annual cloud fraction [0-1] at `latitude_deg` [deg], linear between the
    nodes of `ZONAL_CLOUD_FRACTION` (sources there)."""
    return np.interp(latitude_deg, ZONAL_CLOUD_FRACTION[:, 0], ZONAL_CLOUD_FRACTION[:, 1])


def demo_coverage_map(width: int = 1024, height: int = 512, seed: int = 19,
                      contrast: float = 2.0) -> np.ndarray:
    """A (height, width) coverage map [0-1] (module docstring): the zonal cloud fraction f
    at each latitude, made weather by large-scale noise n,

        m = 1 / (1 + exp(-(4 contrast (n - 1/2) + ln(f / (1 - f)))))

    (a logistic whose midpoint shifts with f, so that where n is 1/2 m = f and the share of
    cloudy pixels grows with f), n the sum of three octaves of domain-warped Perlin noise
    read on the unit sphere (seamless in longitude, no pinch at the poles; systems ~1000-3000
    km across on Earth), equalised to uniform on [0, 1]. Deterministic for a `seed`."""
    from scipy.ndimage import map_coordinates

    from skyscatter.atmosphere.cloud_noise import noise_texture

    size = 64
    tile = noise_texture(seed, size)[..., 0].astype(np.float64)
    latitude = np.radians(90.0 - (np.arange(height) + 0.5) * 180.0 / height)
    longitude = np.radians(-180.0 + (np.arange(width) + 0.5) * 360.0 / width)
    lat, lon = np.meshgrid(latitude, longitude, indexing="ij")
    points = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])

    def noise(p: np.ndarray, scale: float) -> np.ndarray:
        return map_coordinates(tile, p * scale, order=1, mode="grid-wrap")

    warp = np.stack([noise(points + offset, 20.0) - 0.5 for offset in (0.0, 3.1, 5.7)])
    warped = points + 0.25 * warp
    total = sum(noise(warped + 1.3 * octave, 45.0 * 2.0**octave) * 0.55**octave
                for octave in range(3))
    rank = np.argsort(np.argsort(total.ravel())).reshape(total.shape)
    uniform = (rank + 0.5) / rank.size
    zonal = zonal_cloud_fraction(np.degrees(lat))
    # a logistic in the noise, centred so that the share above 0.5 follows the zonal fraction
    logit = np.log(np.clip(zonal, 1e-3, 1 - 1e-3) / np.clip(1 - zonal, 1e-3, 1.0))
    return 1.0 / (1.0 + np.exp(-(contrast * (uniform - 0.5) * 4.0 + logit)))


def read_coverage_map(path: str | Path) -> np.ndarray:
    """The (h, w) coverage map [0-1] in the file `path` (module docstring). InputError naming
    the file and what is wrong for a file that is missing, unreadable, not grey, smaller than
    2 x 2 or larger than `MAX_MAP_PIXELS`, or with values outside [0, 1] or not finite."""
    source = Path(path)
    allowed = ("an equirectangular grey PNG (8 or 16 bit) or a 2-D float .npy array, values "
               "0-1, at least 2 x 2 pixels")
    data = read_user_file(source, _read, what="coverage map", key="coverage_map",
                          allowed=allowed)
    if data.ndim != 2 or min(data.shape) < 2:
        raise InputError(f"coverage map {source}: shape {data.shape} is not allowed: {allowed}",
                         key="coverage_map", value=str(source), allowed=allowed)
    if data.size > MAX_MAP_PIXELS:
        raise InputError(f"coverage map {source}: {data.shape[1]} x {data.shape[0]} pixels, "
                         f"more than {MAX_MAP_PIXELS} (4096 x 2048); scale it down",
                         key="coverage_map", value=str(source), allowed=allowed)
    if not np.all(np.isfinite(data)) or data.min() < 0.0 or data.max() > 1.0:
        raise InputError(f"coverage map {source}: values must be finite and lie in [0, 1] "
                         f"(found {np.nanmin(data):.3g} .. {np.nanmax(data):.3g})",
                         key="coverage_map", value=str(source), allowed="[0, 1]")
    return np.ascontiguousarray(data)


def _read(source: Path) -> np.ndarray:
    if source.suffix.lower() == ".npy":
        data = np.load(source, allow_pickle=False)
        if not np.issubdtype(data.dtype, np.floating):
            raise InputError(f"coverage map {source}: a .npy map holds floats 0-1, not "
                             f"{data.dtype}", key="coverage_map", value=str(source))
        return data.astype(np.float64)
    from PIL import Image

    with Image.open(source) as image:
        if image.mode in ("I;16", "I;16B", "I;16L", "I"):
            return np.asarray(image, dtype=np.float64) / 65535.0
        if image.mode == "L":
            return np.asarray(image, dtype=np.float64) / 255.0
        raise InputError(f"coverage map {source}: a {image.mode} image; give a grey (L or "
                         "16-bit) PNG: the grey level is the coverage factor",
                         key="coverage_map", value=str(source))


def write_coverage_png(path: str | Path, coverage: np.ndarray) -> None:
    """Write a coverage map [0-1] as an 8-bit grey PNG, deterministic bytes."""
    from PIL import Image

    levels = np.round(np.clip(coverage, 0.0, 1.0) * 255.0).astype(np.uint8)
    Image.fromarray(levels).save(path, optimize=True)
