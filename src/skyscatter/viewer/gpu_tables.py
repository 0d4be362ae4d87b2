r"""The precomputed tables in the form the WebGL2 viewer samples: CIE XYZ, float16, in
texture order, packed into one binary message.

The spectral tables (`transport.tables.AtmosphereTables`, n_wl wavelengths) are turned into
three colour channels with the weights C (n_wl, 3) = `cmf_weights` (CIE 1931 XYZ, Y = luminance
[cd m^-2], as `SkyImage.xyz`); the shader turns XYZ into linear sRGB at the end, as
`SkyImage.rgb`. XYZ rather than RGB because its weights are never negative: a channel's
transmittance stays in [0, 1] (an sRGB blue channel weighted by the sun goes negative once the
air has taken the blue out of a long path). Every table that enters the sky radiance linearly
is converted exactly (interpolation commutes with the weighted sum):

  single scattering S_s, orders >= 2 M, indirect irradiance E:   X_c = sum_w C_wc X_w.

Products of spectra cannot be exact in three channels; these are weighted so that the common
case is exact:

  transmittance  T_c = sum_w C_wc E_w T_w / sum_w C_wc E_w  (E = the star's irradiance: the sun
                 disk and the direct sunlight on the ground, E T, are exact);
  ground albedo  a_c = sum_w C_wc E_w a_w / sum_w C_wc E_w;
  phase          p_s,c(theta) = sum_w C_wc p_s,w(theta) k_s,w / sum_w C_wc k_s,w with k_s the
                 table mean of S_s (exact where S_s has that spectral shape; Rayleigh's phase
                 hardly depends on wavelength, an aerosol's forward peak does).

Values are stored divided by a scale per table (header "scales") that puts the largest at
2^14, well inside float16 (max 65504, 11 significant bits, normal down to 6e-5: 9 decades).

Message layout (`encode`): b"SKYT", uint32 format version, uint32 header length n, n bytes of
UTF-8 JSON header, zero padding to a multiple of 4, then the arrays (little-endian float16)
at the byte offsets the header gives. Texture order of each array (`LAYOUT`, C order, last
axis fastest = texture x):
  transmittance (n_r_t, n_mu_t, 3)                 2-D: x = mu, y = r
  irradiance    (n_r_e, n_mu_s_e, 3)               2-D: x = mu_s, y = r
  scattering    (n_t, n_r, n_mu, n_nu, n_mu_s, 3)  3-D: x = nu slice * n_mu_s + mu_s,
                                                   y = mu, z = table * n_r + r
                                                   (tables: S_1 .. S_n_s, then M)
  phase         (n_s * rows, 1024, 3)              2-D, read with texelFetch: angle index i of
                                                   constituent s at row s * rows + i // 1024
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.spectrum.colour import cmf_weights
from skyscatter.spectrum.star import Star
from skyscatter.transport.tables import AtmosphereTables, is_identity_warp

__all__ = ["FORMAT_VERSION", "GpuTables", "LAYOUT", "MAGIC", "MAX_TABLES", "PHASE_ROW",
           "SUN_DISK_SAMPLES", "channel_tables", "decode", "encode", "gpu_tables",
           "pack_message", "scaled_float16", "sun_header", "unpack_message"]

MAGIC = b"SKYT"
FORMAT_VERSION = 2  # 2: the header holds the radius warp
MAX_TABLES = 8  # scattering tables the shader loops over: 7 scattering constituents + orders >= 2
PHASE_ROW = 1024  # texels per row of the phase texture (WebGL2 guarantees 2048)
SUN_DISK_SAMPLES = 33  # limb-darkened disk radiance at cos(limb angle) = 0, 1/32, .., 1
FLOAT16_TARGET = 2.0**14  # the largest value of each table after scaling
LAYOUT = {
    "transmittance": "(n_r_t, n_mu_t, 3): texture x = mu, y = r",
    "irradiance": "(n_r_e, n_mu_s_e, 3): texture x = mu_s, y = r",
    "scattering": "(n_t, n_r, n_mu, n_nu, n_mu_s, 3): texture x = nu * n_mu_s + mu_s, y = mu, "
                  "z = t * n_r + r",
    "phase": f"(n_s * rows, {PHASE_ROW}, 3): angle index i of constituent s at "
             f"(i % {PHASE_ROW}, s * rows + i // {PHASE_ROW})",
}


@dataclass(frozen=True)
class GpuTables:
    """Tables ready for the viewer: `header` (JSON-able: geometry, sizes, scales, the sun's
    XYZ) and float16 `arrays` in texture order (module docstring)."""

    header: dict
    arrays: dict[str, np.ndarray]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.arrays.values())


def _weighted(values: np.ndarray, weights: np.ndarray, light: np.ndarray) -> np.ndarray:
    """sum_w C_wc L_w X_w / sum_w C_wc L_w over the last axis of `values` (..., n_wl)."""
    return (values * light) @ weights / (light @ weights)


def scaled_float16(values: np.ndarray) -> tuple[np.ndarray, float]:
    """(values / scale as float16, scale) with the largest magnitude at FLOAT16_TARGET."""
    largest = float(np.max(np.abs(values))) if values.size else 0.0
    scale = largest / FLOAT16_TARGET if largest > 0.0 else 1.0
    return np.ascontiguousarray(values / scale, dtype=np.float16), scale


def channel_tables(tables: AtmosphereTables, profile: OpticalProfile,
                   weights: np.ndarray, label: str = "", *,
                   transmittance_weights: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The tables of `tables` (computed for `profile`) in texture order (module docstring),
    float64, with one channel per column of `weights` (n_wl, c): CIE XYZ for the viewer,
    linear RGB or the wavelengths themselves (the identity) for `table_export`; the
    transmittance weighted with `transmittance_weights` (default `weights`). Also the
    solar-weighted "ground_albedo" (c,) and the star's "sun_irradiance" (c,) at the top."""
    if not np.array_equal(tables.wavelengths_nm, profile.wavelengths_nm):
        raise InputError("gpu_tables: the tables and the profile have different wavelengths",
                         key="tables", value=tables.wavelengths_nm.size)
    channels = weights.shape[1]
    sun = np.asarray(profile.toa_irradiance, dtype=np.float64)
    n_r, n_mu, n_mu_s, n_nu, n_t, _ = tables.scattering.shape
    n_p = n_t - 1  # the tables weighted by a phase function
    lookup_phase = tables.lookup_phase
    if n_t > MAX_TABLES:
        raise InputError(f"{label or 'this atmosphere'} needs {n_t} scattering tables (its "
                         f"{len(tables.scattering_names)} scattering constituents, the peak "
                         "corrections of those whose forward peak is clipped and the orders "
                         f">= 2); the viewer shows at most {MAX_TABLES}", key="atmosphere",
                         value=label)
    # float32 beyond colour: a spectral set of the full Earth tables is 0.5 GB in float64
    scattering = np.empty((n_t, n_r, n_mu, n_nu, n_mu_s, channels),
                          dtype=np.float64 if channels <= 3 else np.float32)
    phase_rows = -(-lookup_phase.shape[1] // PHASE_ROW)
    phase = np.zeros((n_p, phase_rows * PHASE_ROW, channels))
    for t in range(n_t):
        table = tables.scattering[..., t, :].astype(np.float64)
        scattering[t] = np.moveaxis(table @ weights, 3, 2)  # (r, mu, nu, mu_s, c)
        if t < n_p:
            mean = table.reshape(-1, table.shape[-1]).mean(axis=0)
            phase[t, :lookup_phase.shape[1]] = _weighted(lookup_phase[t], weights, mean)
    if transmittance_weights is None:
        transmittance_weights = weights
    return {"transmittance": _weighted(tables.transmittance, transmittance_weights, sun),
            "irradiance": tables.irradiance @ weights,
            "scattering": scattering,
            "phase": phase.reshape(n_p * phase_rows, PHASE_ROW, channels),
            "ground_albedo": _weighted(np.asarray(profile.ground_albedo, dtype=np.float64),
                                       weights, sun),
            "sun_irradiance": sun @ weights}


def gpu_tables(tables: AtmosphereTables, profile: OpticalProfile, star: Star,
               label: str = "") -> GpuTables:
    """The viewer's tables of `tables` (computed for `profile`, lit by `star`)."""
    weights = cmf_weights(profile.wavelengths_nm)
    channels = channel_tables(tables, profile, weights, label)
    scattering = channels["scattering"]
    n_t, n_r, n_mu, n_nu, n_mu_s, _ = scattering.shape
    phase_rows = channels["phase"].shape[0] // (n_t - 1)
    albedo = channels["ground_albedo"]
    arrays, scales = {}, {}
    for name in ("transmittance", "irradiance", "phase"):
        arrays[name], scales[name] = scaled_float16(channels[name])
    packed = np.empty(scattering.shape, dtype=np.float16)
    table_scales = []
    for t in range(n_t):
        packed[t], scale = scaled_float16(scattering[t])
        table_scales.append(scale)
    arrays["scattering"] = packed
    scales["scattering"] = table_scales
    header = {
        "label": label,
        "bottom_radius_m": float(tables.bottom_radius_m),
        "top_radius_m": float(tables.top_radius_m),
        "mu_s_min": float(tables.min_cos_sun_zenith),
        "sun_angle_share": float(tables.sun_angle_share),
        "radius_warp": [float(v) for v in tables.radius_warp],
        # Bruneton's axis: the shader skips the warp's reads (docs/viewer.md, GPU frame time)
        "radius_warp_identity": is_identity_warp(tables.radius_warp),
        "orders": int(tables.orders),
        "n_wavelengths": int(profile.n_wavelengths),
        "scattering_names": list(tables.scattering_names),
        "peak_correction_names": list(tables.peak_correction_names),
        "scattering_shape": [int(n_r), int(n_mu), int(n_mu_s), int(n_nu), int(n_t)],
        "transmittance_shape": [int(n) for n in tables.transmittance.shape[:2]],
        "irradiance_shape": [int(n) for n in tables.irradiance.shape[:2]],
        "phase_angles": int(tables.phase.shape[1]),
        "phase_rows": int(phase_rows),
        "scales": scales,
        "ground_albedo_xyz": [float(v) for v in albedo],
        **sun_header(profile, star, weights),
    }
    return GpuTables(header, arrays)


def sun_header(profile: OpticalProfile, star: Star, weights: np.ndarray) -> dict:
    """The star as the viewer draws it, in the channels of `weights` (n_wl, 3): its
    irradiance at the top ("sun_irradiance_xyz"), angular radius, solid angle and the
    limb-darkened disk radiance at SUN_DISK_SAMPLES cosines of the limb angle."""
    cos_limb = np.linspace(0.0, 1.0, SUN_DISK_SAMPLES)
    disk = star.disk_radiance(profile.wavelengths_nm, cos_limb) @ weights
    sun = np.asarray(profile.toa_irradiance, dtype=np.float64) @ weights
    return {"sun_irradiance_xyz": [float(v) for v in sun],
            "sun_angular_radius_rad": float(profile.sun_angular_radius_rad),
            "sun_solid_angle_sr": float(star.solid_angle_sr),
            "sun_disk_xyz": [[float(v) for v in row] for row in disk]}


def encode(gpu: GpuTables) -> bytes:
    """The binary message of `gpu` (module docstring)."""
    return pack_message((MAGIC, FORMAT_VERSION), gpu.header, gpu.arrays)


def pack_message(magic_and_version: tuple[bytes, int], header: dict,
                 arrays: dict[str, np.ndarray]) -> bytes:
    """The binary message `unpack_message` reads: the magic, the version, the JSON header with
    each array's offset, shape and dtype (float16 arrays as float16, the rest as float32), then
    the arrays, little-endian, the first 4-byte aligned (typed-array views in JavaScript)."""
    magic, version = magic_and_version
    offsets, blobs, position = {}, [], 0
    for name, array in arrays.items():
        dtype = "float16" if array.dtype == np.float16 else "float32"
        blob = array.astype("<f2" if dtype == "float16" else "<f4", copy=False).tobytes()
        offsets[name] = {"offset": position, "shape": list(array.shape), "dtype": dtype}
        blobs.append(blob)
        position += len(blob)
    text = json.dumps(dict(header, arrays=offsets), separators=(",", ":")).encode()
    text += b" " * (-(len(text) + 12) % 4)
    return b"".join([magic, struct.pack("<II", version, len(text)), text, *blobs])


def decode(message: bytes) -> GpuTables:
    """Inverse of `encode` (for tests and tools; the viewer decodes in JavaScript)."""
    return GpuTables(*unpack_message(message, (MAGIC, FORMAT_VERSION), "table"))


def unpack_message(message: bytes, magic_and_version: tuple[bytes, int],
                   what: str) -> tuple[dict, dict[str, np.ndarray]]:
    """(header, arrays) of a binary message: the magic, its version and the header's length
    (little-endian uint32s), the JSON header, then the arrays at the header's offsets
    (float16, or float32 where its entry's dtype says so)."""
    magic, expected = magic_and_version
    if message[:4] != magic or len(message) < 12:
        raise InputError(f"not a skyscatter {what} message (no {magic.decode()} magic)",
                         key="message", value=message[:4])
    version, length = struct.unpack("<II", message[4:12])
    if version != expected:
        raise InputError(f"{what} message version {version}, expected {expected}",
                         key="version", value=version)
    header = json.loads(message[12:12 + length])
    start = 12 + length
    arrays = {}
    for name, entry in header.pop("arrays").items():
        count = int(np.prod(entry["shape"]))
        dtype = "<f4" if entry.get("dtype") == "float32" else "<f2"
        arrays[name] = np.frombuffer(message, dtype, count, start + entry["offset"]).reshape(
            entry["shape"])
    return header, arrays
