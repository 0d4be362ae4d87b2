"""The viewer's sky of one instant as JSON: the sun's place and the star field the client draws.

`sky_message(body, observer, star)` answers the server's /api/sky request
(`viewer.server.SkyAt`): the sun's apparent zenith and azimuth [deg], the time in UTC, how much
more the sun lights the planet at its distance then than the config's `star` does
(`Star.irradiance_scale_at`, as `render --time`), and the stars brighter than
`MAGNITUDE_LIMIT` with their apparent east-north-up directions (refracted, as
`render.sky_at_time` draws them) and their CIE XYZ irradiance at the top of the atmosphere
(`render.sky_at_time.star_field` on the wavelength bins of `render`).
"""

from __future__ import annotations

import numpy as np

from skyscatter.render.sky_at_time import Observer, apparent_directions, ephemeris, star_field
from skyscatter.spectrum.colour import spectral_to_xyz
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.spectrum.star import Star

__all__ = ["MAGNITUDE_LIMIT", "STAR_GRID", "sky_message"]

# Stars the viewer draws (brighter than V 6.5: about 9100, half of them up at a time) and the
# wavelength bins of their colour (those of `render`)
MAGNITUDE_LIMIT = 6.5
STAR_GRID = wavelength_grid(DEFAULT_WAVELENGTH_BINS)


def sky_message(body: str, observer: Observer, star: Star) -> dict:
    """The JSON-ready sky of `observer` on planet `body` ("earth" or "mars") lit by `star` (at
    the config's distance): keys sun_zenith_deg, sun_azimuth_deg (from north towards east),
    time_utc (ISO 8601), sun_light_scale (the star's light at the date's distance over its
    light at the config's: (d_config / d)^2) and stars
    (count, directions_enu: flat list of unit vectors to 7 decimals, irradiance_xyz: flat list
    of their XYZ (`spectrum.colour.spectral_to_xyz` of the irradiance) to 5 significant
    digits)."""
    sky = ephemeris(body, observer)
    directions, irradiance = star_field(sky, MAGNITUDE_LIMIT, STAR_GRID)
    xyz = spectral_to_xyz(irradiance, STAR_GRID)
    east, north, up = apparent_directions(sky, sky.sun.direction())
    return {"sun_zenith_deg": float(np.degrees(np.arccos(np.clip(up, -1.0, 1.0)))),
            "sun_azimuth_deg": float(np.degrees(np.arctan2(east, north)) % 360.0),
            "time_utc": observer.time_utc.isoformat(),
            "sun_light_scale": star.irradiance_scale_at(sky.sun.distance_m),
            "stars": {"count": int(directions.shape[0]),
                      "directions_enu": np.round(directions, 7).reshape(-1).tolist(),
                      "irradiance_xyz": [float(f"{v:.5g}") for v in xyz.reshape(-1)]}}
