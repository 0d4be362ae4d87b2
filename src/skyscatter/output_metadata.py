"""The metadata of a table of results: what a scientist needs to cite and repeat it.

`output_metadata` describes one run of `sky_radiance_rows` or `irradiance_rows` (and the
datasets made from them): the units and meaning of every column (`COLUMNS`, units in the
UDUNITS spelling that CF conventions use: "W m-2 sr-1 nm-1"), the atmosphere (preset name or
config path, the SHA-256 of the file and of the optical profile the solver saw: the same
fingerprint that keys the table cache, `transport.cache.profile_fingerprint`), the solver and
the options it used, the wavelengths, the geometry, the solar spectrum, the package version
and the time of computation (UTC; `$SOURCE_DATE_EPOCH` fixes it for reproducible files,
https://reproducible-builds.org/specs/source-date-epoch/).
"""

from __future__ import annotations

import datetime
import hashlib
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from skyscatter import __version__
from skyscatter.atmosphere.config import PRESETS_DIR
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.errors import InputError
from skyscatter.row_output import SIGNIFICANT_DIGITS
from skyscatter.transport.cache import profile_fingerprint
from skyscatter.transport.solvers import SolverOptions

__all__ = ["COLUMNS", "output_metadata"]

# column -> (units, long name); one entry per column any row of the API can have
COLUMNS: dict[str, tuple[str, str]] = {
    "sun_zenith_deg": ("degree", "sun zenith angle"),
    "view_zenith_deg": ("degree", "view zenith angle (0 looks straight up)"),
    "relative_azimuth_deg": ("degree", "view azimuth relative to the sun (0 looks towards it)"),
    "wavelength_nm": ("nm", "wavelength (centre of a 1 nm cell)"),
    "radiance": ("W m-2 sr-1 nm-1", "diffuse spectral sky radiance (the sun's disk left out)"),
    "standard_error": ("W m-2 sr-1 nm-1", "standard error of the Monte Carlo radiance"),
    "toa_irradiance": ("W m-2 nm-1", "spectral solar irradiance at the top of the atmosphere, "
                       "normal to the beam"),
    "direct_normal": ("W m-2 nm-1", "direct spectral irradiance normal to the sun's beam"),
    "diffuse_horizontal": ("W m-2 nm-1", "diffuse spectral irradiance on a horizontal plane"),
    "global_horizontal": ("W m-2 nm-1", "global (direct + diffuse) spectral irradiance on a "
                          "horizontal plane"),
    "direct_transmittance": ("1", "transmittance of the direct beam from the top of the "
                             "atmosphere (direct_normal / toa_irradiance)"),
    "sun_azimuth_deg": ("degree", "sun azimuth from north towards east"),
    "sun_distance_m": ("m", "distance of the star at the time, by which the light is scaled "
                       "(inverse-square law) from the config's distance"),
    "tilt_deg": ("degree", "tilt of the plane from the horizontal"),
    "plane_azimuth_deg": ("degree", "azimuth the plane faces, from north towards east"),
    "plane_direct": ("W m-2 nm-1", "direct spectral irradiance on the plane"),
    "plane_sky_diffuse": ("W m-2 nm-1", "spectral irradiance on the plane from the sky's "
                          "radiance distribution"),
    "plane_ground_reflected": ("W m-2 nm-1", "spectral irradiance on the plane from the "
                               "Lambertian ground"),
    "plane_global": ("W m-2 nm-1", "total spectral irradiance on the plane"),
}

_SPECTRA = {"astm-g173": "ASTM G173-03 extraterrestrial spectrum (ASTM International 2012, "
                         "doi:10.1520/G0173-03R12), scaled to the star's distance",
            "blackbody": "Planck spectrum of the star's effective temperature"}


def output_metadata(atmosphere: Atmosphere, columns: Sequence[str],
                    wavelengths_nm: Sequence[float], *, solver: str = "lut",
                    options: SolverOptions | None = None,
                    geometry: Mapping[str, object] | None = None) -> dict:
    """A JSON-ready dict describing a table of `columns` (names in `COLUMNS`) computed for
    `atmosphere` by `solver` with `options` (default: the config's orders, 64 samples) at the
    monochromatic `wavelengths_nm`; `geometry` (angles, altitude, time) is copied as given.
    InputError for a column that has no description."""
    unknown = [name for name in columns if name not in COLUMNS]
    if unknown:
        raise InputError(f"no units are known for the column(s) {', '.join(unknown)}",
                         key="columns", value=unknown, allowed=", ".join(COLUMNS))
    options = options or SolverOptions(orders=atmosphere.scattering_orders)
    wavelengths = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    profile = atmosphere.optical_profile(wavelengths, monochromatic=True)
    star = atmosphere.planet.star
    return {
        "software": "skyscatter",
        "version": __version__,
        "computed_utc": _now_utc(),
        "atmosphere": _atmosphere(atmosphere, profile_fingerprint(profile)),
        "solver": _solver(solver, options),
        "wavelengths_nm": [float(w) for w in wavelengths],
        "geometry": dict(geometry or {}),
        "solar_spectrum": {"type": star.spectrum, "source": _SPECTRA.get(star.spectrum, ""),
                           "distance_m": float(star.distance_m)},
        "number_format": f"{SIGNIFICANT_DIGITS} significant digits",
        "columns": {name: {"units": COLUMNS[name][0], "long_name": COLUMNS[name][1]}
                    for name in columns},
    }


def _atmosphere(atmosphere: Atmosphere, fingerprint: str) -> dict:
    """Name, preset or config path, and the SHA-256 of the file and of the optical profile."""
    described: dict[str, str] = {"name": atmosphere.name}
    source = Path(atmosphere.source) if atmosphere.source else None
    if source is not None and source.parent.resolve() == PRESETS_DIR.resolve():
        described["preset"] = source.stem
    elif source is not None:
        described["config"] = str(source)
    if source is not None and source.is_file():
        described["config_sha256"] = hashlib.sha256(source.read_bytes()).hexdigest()
    described["optical_profile_sha256"] = fingerprint
    return described


def _solver(name: str, options: SolverOptions) -> dict:
    """The solver's name and the options that concern it (`transport.solvers.SolverOptions`)."""
    if name == "lut":
        return {"name": name, "orders": int(options.orders)}
    if name == "montecarlo":
        return {"name": name, "samples": int(options.n_samples), "seed": int(options.seed)}
    return {"name": name, "samples": int(options.n_samples)}


def _now_utc() -> str:
    """ISO 8601 UTC time to the second, or `$SOURCE_DATE_EPOCH`'s when that is set."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    moment = (datetime.datetime.fromtimestamp(int(epoch), datetime.UTC) if epoch.isdigit()
              else datetime.datetime.now(datetime.UTC))
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")
