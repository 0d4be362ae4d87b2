r"""The precomputed tables as files for engines: transmittance, irradiance, scattering and phase
textures in the viewer's texture layout, a JSON sidecar with every constant a shader needs, and
the GLSL and HLSL that read them (`skyscatter export-tables`, `api.export_tables`).

Tables (`gpu_tables.channel_tables`: the viewer's layout, channels chosen by `colour`):

  transmittance  2-D, width n_mu_t, height n_r_t: T to the top of the air [-]
  irradiance     2-D, width n_mu_s_e, height n_r_e: indirect irradiance on the ground
  scattering     3-D, width n_nu * n_mu_s, height n_mu, depth n_tables * n_r: the 4-D table
                 (r, mu, mu_s, nu) packed as Bruneton's 2017 reference packs it (and Unreal
                 Engine 4's Atmospheric Fog, from Bruneton & Neyret 2008), the nu axis
                 folded into x: texel (x, y, z) holds
                 nu index x // n_mu_s, mu_s index x % n_mu_s, mu index y, r index z % n_r of
                 table z // n_r; tables S_1 .. S_n_s (single scattering of each scattering
                 constituent, without its phase function), then D_1 .. D_n_c (the peak
                 corrections of the constituents whose forward peak is clipped, without
                 phase function; none for clear air), then M (orders >= 2, phases in)
  phase          2-D, width 1024: phase function of table t (< n_tables - 1) at angle index i
                 in texel (i % 1024, t * rows + i // 1024), angles uniform over [0, pi]
                 [sr^-1]: p_s of the constituents, then the clipped p*_c of the peak
                 corrections

The coordinates within each axis are skyscatter's (transport/table_parameterisation.py, with
its GLSL twin in the snippets), not Bruneton's: a horizon-dense mu axis, a mu_s axis that
reaches below the horizon with part of it uniform in sin(sun zenith / 2), and a warp of the
radius axis; sky.glsl's `sky_radiance` does the lookups. Values are stored divided by a
scale per table (sidecar "scales"; 1 for float32; for float16 the largest value at 2^14).

Channels (`colour`): "xyz" CIE 1931 XYZ (Y luminance [cd m^-2], irradiance in lux), as the
viewer; "rgb" linear RGB of `colour_space`, 1.0 = 1 cd m^-2 of luminance (the weights of XYZ
turned into RGB, `spectrum.colour.xyz_to_rgb`: exact for the tables that enter the radiance
linearly; transmittance weighted by the sun's spectrum as in `gpu_tables`, but through the
positive part of each channel's weights: with the negative lobes of an RGB space's weights the
blue transmittance of a long, reddened path goes negative, and the ratio of two of them that
sky.glsl takes for a segment of a ray loses the ground's blue); "spectral"
one channel per wavelength, in SI units (docs/engines.md lists them), named as Fichet et al.
2021 name spectral EXR channels ("S0.550,000000nm").

Files: exr (one file per table, the 3-D table as an atlas of its z slices stacked downwards:
row z * n_mu + y), ktx2 (`viewer.ktx2`, RGBA, the 3-D table a 3-D texture; spectral: one file
per group of 4 wavelengths, name_<group>.ktx2, the last group padded with zeros) or npz (one
archive, arrays by name in texture order (depth, height, width, channels)). Row 0 of every
file is texture coordinate 0, in OpenGL and Direct3D alike. A folder is written whole:
temporaries, then renamed (`output_files.staged_outputs`).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skyscatter import __version__
from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.output_files import check_writable_folder, staged_outputs
from skyscatter.render.image_io import exr_writer
from skyscatter.render.spectral_exr import FICHET2021_ATTRIBUTES, fichet2021_channel_name
from skyscatter.spectrum.colour import (
    RGB_SPACES,
    cmf_weights,
    rgb_space_chromaticities,
    xyz_to_rgb,
)
from skyscatter.transport.cache import profile_fingerprint
from skyscatter.transport.tables import AtmosphereTables, is_identity_warp
from skyscatter.viewer.gpu_tables import LAYOUT, PHASE_ROW, channel_tables, scaled_float16
from skyscatter.viewer.ktx2 import ktx2_bytes
from skyscatter.viewer.shader_export import glsl_snippet, hlsl_snippet

__all__ = ["COLOURS", "ExportedTables", "FORMATS", "GLSL_FILE", "HLSL_FILE", "OWNED",
           "PRECISIONS", "SIDECAR", "TABLES", "ExportSettings", "channel_weights", "export_tables",
           "texture_arrays"]

FORMATS = ("exr", "ktx2", "npz")
COLOURS = ("rgb", "xyz", "spectral")
PRECISIONS = {"half": np.float16, "float": np.float32}
TABLES = ("transmittance", "irradiance", "scattering", "phase")
SIDECAR = "tables.json"
GLSL_FILE = "skyscatter_tables.glsl"
HLSL_FILE = "skyscatter_tables.hlsl"
# What an export folder holds (it is replaced as a whole)
OWNED = re.compile(r"(transmittance|irradiance|scattering|phase)(_[0-9]+)?\.(exr|ktx2)"
                   r"|tables\.(npz|json)|skyscatter_tables\.(glsl|hlsl)")
SIDECAR_FORMAT = 1
# The KTX2 DFD's colorPrimaries of each colour space (Data Format spec, khr_df_primaries_e)
_KTX2_PRIMARIES = {"srgb": "bt709", "rec709": "bt709", "rec2020": "bt2020",
                   "display-p3": "displayp3", "acescg": "acescc", "aces2065-1": "aces"}
_UNITS = {  # of each table's values times its scale, per colour
    "xyz": {"transmittance": "1", "irradiance": "lx (Y)",
            "scattering": "cd m^-2 (Y); the single-scattering tables times their phase function",
            "phase": "sr^-1"},
    "spectral": {"transmittance": "1", "irradiance": "W m^-2 nm^-1",
                 "scattering": "W m^-2 sr^-1 nm^-1 (single-scattering tables: W m^-2 nm^-1, "
                               "times the phase [sr^-1])", "phase": "sr^-1"},
}
_UNITS["rgb"] = {name: text.replace("(Y)", "(luminance of RGB)")
                 for name, text in _UNITS["xyz"].items()}


@dataclass(frozen=True)
class ExportSettings:
    """How to export: file `format` (FORMATS), `colour` (COLOURS), the RGB `colour_space`
    (RGB_SPACES; used for "rgb"), `precision` (PRECISIONS) and the atmosphere's `label`."""

    format: str = "exr"
    colour: str = "rgb"
    colour_space: str = "srgb"
    precision: str = "half"
    label: str = ""

    def check(self) -> None:
        """InputError for an unknown format, colour, colour space or precision."""
        for key, value, allowed in (("format", self.format, FORMATS),
                                    ("colour", self.colour, COLOURS),
                                    ("colour_space", self.colour_space, tuple(RGB_SPACES)),
                                    ("precision", self.precision, tuple(PRECISIONS))):
            if value not in allowed:
                raise InputError(f"unknown {key.replace('_', ' ')} {value!r}; choose one of "
                                 f"{', '.join(allowed)}", key=key, value=value,
                                 allowed=", ".join(allowed))


@dataclass(frozen=True)
class ExportedTables:
    """What `export_tables` wrote: the folder, its files and the sidecar's content."""

    folder: Path
    files: tuple[Path, ...]
    sidecar: dict


def channel_weights(wavelengths_nm: np.ndarray, colour: str,
                    colour_space: str = "srgb") -> tuple[np.ndarray, tuple[str, ...]]:
    """(weights (n_wl, c), channel names) of `colour` (module docstring)."""
    if colour == "spectral":
        return (np.eye(wavelengths_nm.size),
                tuple(fichet2021_channel_name(w) for w in wavelengths_nm))
    weights = cmf_weights(wavelengths_nm)
    if colour == "rgb":
        return xyz_to_rgb(weights, colour_space), ("R", "G", "B")
    return np.array(weights), ("X", "Y", "Z")


def _stored(values: np.ndarray, dtype: type) -> tuple[np.ndarray, float]:
    """(values / scale in `dtype`, scale): float16 scaled as the viewer's tables, float32 as
    they are."""
    if dtype is np.float16:
        return scaled_float16(values)
    return np.ascontiguousarray(values, dtype=np.float32), 1.0


def texture_arrays(tables: AtmosphereTables, profile: OpticalProfile, weights: np.ndarray,
                   precision: str = "half", label: str = ""
                   ) -> tuple[dict[str, np.ndarray], dict, dict[str, np.ndarray]]:
    """(arrays by name in texture order (depth, height, width, c) or (height, width, c),
    scales by name (a list for the scattering tables), the channel tables' ground albedo and
    sun irradiance); `weights` from `channel_weights`."""
    # RGB: the transmittance through the positive part of each channel's weights (module
    # docstring); XYZ's and the wavelengths' weights are never negative
    channels = channel_tables(tables, profile, weights, label,
                              transmittance_weights=np.maximum(weights, 0.0))
    dtype = PRECISIONS[precision]
    arrays, scales = {}, {}
    for name in ("transmittance", "irradiance", "phase"):
        arrays[name], scales[name] = _stored(channels[name], dtype)
    scattering = channels["scattering"]
    n_t, n_r, n_mu, n_nu, n_mu_s, c = scattering.shape
    packed = np.empty(scattering.shape, dtype=dtype)
    scales["scattering"] = []
    for t in range(n_t):
        packed[t], scale = _stored(scattering[t], dtype)
        scales["scattering"].append(scale)
    arrays["scattering"] = packed.reshape(n_t * n_r, n_mu, n_nu * n_mu_s, c)
    extras = {name: channels[name] for name in ("ground_albedo", "sun_irradiance")}
    return arrays, scales, extras


def _uniforms(tables: AtmosphereTables, profile: OpticalProfile, arrays: dict, scales: dict,
              extras: dict) -> dict:
    """The values of sky.glsl's and parameterisation.glsl's uniforms (their names)."""
    n_r, n_mu, n_mu_s, n_nu, n_t, _ = tables.scattering.shape
    warp = np.zeros(4 * -(-tables.radius_warp.size // 4))
    warp[:tables.radius_warp.size] = tables.radius_warp
    uniforms = {
        "u_transmittance_size": [arrays["transmittance"].shape[1],
                                 arrays["transmittance"].shape[0]],
        "u_irradiance_size": [arrays["irradiance"].shape[1], arrays["irradiance"].shape[0]],
        "u_scattering_shape": [n_r, n_mu, n_mu_s, n_nu],
        "u_n_tables": n_t,
        "u_phase_angles": tables.phase.shape[1],
        "u_phase_rows": arrays["phase"].shape[0] // (n_t - 1),
        "u_transmittance_scale": scales["transmittance"],
        "u_irradiance_scale": scales["irradiance"],
        "u_phase_scale": scales["phase"],
        "u_scattering_scales": scales["scattering"],
        "u_bottom_radius": tables.bottom_radius_m,
        "u_top_radius": tables.top_radius_m,
        "u_mu_s_min": tables.min_cos_sun_zenith,
        "u_sun_angle_share": tables.sun_angle_share,
        "u_sun_angular_radius": profile.sun_angular_radius_rad,
        "u_radius_warp": warp.tolist(),
        "u_radius_warp_identity": int(is_identity_warp(tables.radius_warp)),
    }
    if extras["sun_irradiance"].size == 3:  # the snippet's vec3 colour uniforms
        uniforms["u_ground_albedo"] = extras["ground_albedo"].tolist()
        uniforms["u_sun_irradiance"] = extras["sun_irradiance"].tolist()
    return {key: (float(value) if isinstance(value, float | np.floating) else value)
            for key, value in uniforms.items()}


def _layout(name: str) -> str:
    """The viewer's layout of table `name` (`gpu_tables.LAYOUT`) for any number of channels."""
    return LAYOUT[name].replace(", 3)", ", channels)")


def _file_names(name: str, output_format: str, channels: int) -> list[str]:
    if output_format == "ktx2" and channels > 4:
        return [f"{name}_{g}.ktx2" for g in range(-(-channels // 4))]
    return [f"{name}.{output_format}"]


def _sidecar(tables: AtmosphereTables, profile: OpticalProfile, settings: ExportSettings,
             names: tuple[str, ...], arrays: dict, scales: dict, extras: dict) -> dict:
    """The JSON sidecar (docs/engines.md, "Exported tables")."""
    output_format, colour, rgb = settings.format, settings.colour, settings.colour == "rgb"
    n_r, n_mu, n_mu_s, n_nu, n_t, _ = tables.scattering.shape
    files = {}
    for name, array in arrays.items():
        depth, height, width = (array.shape[:3] if array.ndim == 4
                                else (0, *array.shape[:2]))
        files[name] = {"files": _file_names(name, output_format, len(names)),
                       "texture": "3D" if depth else "2D", "width": width, "height": height,
                       "depth": depth, "layout": _layout(name),
                       "units": _UNITS[colour][name]}
    return {
        "format": "skyscatter-tables", "format_version": SIDECAR_FORMAT,
        "skyscatter_version": __version__, "atmosphere": settings.label,
        "atmosphere_fingerprint": profile_fingerprint(profile),
        "file_format": output_format, "precision": settings.precision,
        "colour": colour, "colour_space": settings.colour_space if rgb else None,
        "chromaticities": list(rgb_space_chromaticities(settings.colour_space)) if rgb else None,
        "channels": list(names), "wavelengths_nm": profile.wavelengths_nm.tolist(),
        "bottom_radius_m": float(tables.bottom_radius_m),
        "top_radius_m": float(tables.top_radius_m),
        "mu_s_min": float(tables.min_cos_sun_zenith),
        "sun_angle_share": float(tables.sun_angle_share),
        "sun_angular_radius_rad": float(profile.sun_angular_radius_rad),
        "radius_warp": tables.radius_warp.tolist(),
        "radius_warp_identity": is_identity_warp(tables.radius_warp),
        "orders": int(tables.orders), "scattering_names": list(tables.scattering_names),
        "peak_correction_names": list(tables.peak_correction_names),
        "scattering_shape": {"n_r": n_r, "n_mu": n_mu, "n_mu_s": n_mu_s, "n_nu": n_nu,
                             "n_tables": n_t},
        "phase_angles": int(tables.phase.shape[1]), "phase_row": PHASE_ROW,
        "scales": scales,
        "ground_albedo": extras["ground_albedo"].tolist(),
        "sun_irradiance": extras["sun_irradiance"].tolist(),
        "sun_irradiance_units": _UNITS[colour]["irradiance"],
        "tables": files,
        "uniforms": _uniforms(tables, profile, arrays, scales, extras),
        "shaders": {"glsl": GLSL_FILE, "hlsl": HLSL_FILE},
    }


def _write_texture(folder: Path, name: str, array: np.ndarray, settings: ExportSettings,
                   names: tuple[str, ...], scale: float | list[float]) -> None:
    """One table's file(s) in `folder` (a staged temporary folder)."""
    if settings.format == "exr":
        atlas = array.reshape(-1, *array.shape[-2:])  # 3-D: z slices stacked downwards
        attributes = {"skyscatter_table": name, "skyscatter_scale": json.dumps(scale),
                      "skyscatter_layout": _layout(name),
                      # the layout's version; its emissiveUnits (radiance) fit no table but one
                      **({"spectralLayoutVersion": FICHET2021_ATTRIBUTES["spectralLayoutVersion"]}
                         if settings.colour == "spectral" else {})}
        exr_writer(atlas, names, attributes,
                   chromaticities=rgb_space_chromaticities(settings.colour_space)
                   if settings.colour == "rgb" else None)(str(folder / f"{name}.exr"))
        return
    primaries = {"xyz": "ciexyz", "rgb": _KTX2_PRIMARIES[settings.colour_space]}.get(
        settings.colour, "unspecified")
    groups = -(-array.shape[-1] // 4)
    padded = np.zeros(array.shape[:-1] + (4 * groups,), dtype=array.dtype)
    padded[..., :array.shape[-1]] = array
    for g, file_name in enumerate(_file_names(name, "ktx2", len(names))):
        data = ktx2_bytes(padded[..., 4 * g:4 * g + 4], primaries, f"skyscatter {__version__}")
        (folder / file_name).write_bytes(data)


def export_tables(tables: AtmosphereTables, profile: OpticalProfile, folder: str | Path,
                  settings: ExportSettings) -> ExportedTables:
    """Write the tables of `tables` (computed for `profile`) into `folder`, which is replaced
    as a whole, as `settings` say (module docstring). Returns what was written."""
    settings.check()
    target = check_writable_folder(folder, OWNED)
    weights, names = channel_weights(profile.wavelengths_nm, settings.colour,
                                     settings.colour_space)
    arrays, scales, extras = texture_arrays(tables, profile, weights, settings.precision,
                                            settings.label)
    sidecar = _sidecar(tables, profile, settings, names, arrays, scales, extras)
    with staged_outputs() as stage:
        staging = stage.folder(target)
        if settings.format == "npz":
            np.savez(staging / "tables.npz", wavelengths_nm=profile.wavelengths_nm, **arrays)
        else:
            for name, array in arrays.items():
                _write_texture(staging, name, array, settings, names, scales[name])
        (staging / SIDECAR).write_text(json.dumps(sidecar, indent=1) + "\n")
        (staging / GLSL_FILE).write_text(glsl_snippet())
        (staging / HLSL_FILE).write_text(hlsl_snippet())
        written = sorted(path.name for path in staging.iterdir())
    return ExportedTables(target, tuple(target / name for name in written), sidecar)
