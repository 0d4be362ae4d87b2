r"""Cloud layers in the form the WebGL2 viewer samples: the arrays of a `CloudField`
(`atmosphere.cloud_field`) with the optics in CIE XYZ, packed into one binary message.

The shader (`static/shaders/clouds.glsl`) marches the same water content w(p) as the CPU
renderer (`atmosphere._cloud_sampling._water`), from the same noise tile and the same
parameter table, and lights it as `transport._cloud_kernels` does. What changes on the way:

* The noise tile (n, n, n, 2) of each layer, float16 (11 significant bits: the equalised
  shape noise is kept to 2.4e-4, a 360th of the narrowest edge ramp of the presets, edge
  0.25 x coverage 0.35 = 0.0875), as one RG16F 3-D texture, the layers stacked along its depth
  (the array's first axis, the world x of the tile), each followed by a copy of its first
  slice, so that hardware trilinear filtering wraps around inside a layer (the shader keeps
  the depth coordinate in [0.5, n + 0.5) texels). Width and height wrap with REPEAT.
* The optics per gram of water as the CPU renderer's kernels take them
  (`transport.clouds.kernel_arrays`: with any scaling it applies, such as a delta-scaled
  forward peak), which it keeps per wavelength, per XYZ channel, weighted by the star's
  spectrum as `gpu_tables` weights the transmittance:

      k_c = sum_w C_wc E_w k_w / sum_w C_wc E_w     (k: mass extinction, single-scattering
                                                     albedo, asymmetry, phase function)

  with C the CIE 1931 weights and E the star's top-of-atmosphere irradiance. Cloud particles
  are nearly grey across the visible (droplets of r_eff 7 µm: k_ext within 3 %), so the
  products of spectra the renderer forms (E T_air ω p e^(-k W)) are near their channel
  products; the test compares the images (tests/viewer/test_viewer_browser.py).
* The parameter table as float32, its columns named in `static/generated/cloud_layout.json`
  (from `_cloud_sampling`, by `codegen`): the page fills the wind's columns (offset, along)
  from the place and the clouds' time itself, as `cloud_field` does with `to_world` and
  `time_s`.
* The share of the sky's light the ground keeps under the clouds (`transport.clouds.
  ground_shade`, weighted as the optics) in the header: the page keeps the preset's when its
  coverage control changes the coverage.

Message layout (`encode`): b"SKYC", uint32 format version, uint32 header length n, n bytes of
UTF-8 JSON header, zero padding to a multiple of 4, then the arrays (little-endian) at the byte
offsets and with the dtypes the header gives:
  noise     (n_layers * (n + 1), n, n, 2) float16   3-D RG: x = z, y = y, depth = layer, x
  params    (n_layers, N_PARAMS) float32            read with texelFetch
  profiles  (n_layers, n_rows, 2) float32            the profile's nodes first (the column
                                                    statistics and coverage maps after them
                                                    are not read: not drawn yet)
  phase     (n_layers, PHASE_ANGLES, 3) float32     XYZ, texelFetch at angle node i
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.atmosphere.cloud_config import Clouds
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.spectrum.colour import cmf_weights
from skyscatter.transport.clouds import ground_shade, kernel_arrays
from skyscatter.viewer.gpu_tables import pack_message, unpack_message

__all__ = ["CLOUD_FORMAT_VERSION", "CLOUD_LAYOUT", "CLOUD_MAGIC", "GpuClouds", "decode_clouds",
           "encode_clouds", "gpu_clouds"]

CLOUD_MAGIC = b"SKYC"
CLOUD_FORMAT_VERSION = 1
CLOUD_LAYOUT = {
    "noise": "(n_layers * (n + 1), n, n, 2) float16: 3-D RG texture, x = tile z, y = tile y, "
             "depth = layer * (n + 1) + tile x (slice n repeats slice 0)",
    "params": "(n_layers, N_PARAMS) float32: columns as `columns`",
    "profiles": "(n_layers, n_rows, 2) float32: (height fraction, factor) of the profile's "
                "N_PROFILE nodes first",
    "phase": "(n_layers, PHASE_ANGLES, 3) float32: XYZ-weighted phase [sr^-1] at "
             "theta = pi (i / (PHASE_ANGLES - 1))^2",
}


@dataclass(frozen=True)
class GpuClouds:
    """Clouds ready for the viewer: `header` (JSON-able) and `arrays` (module docstring)."""

    header: dict
    arrays: dict[str, np.ndarray]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.arrays.values())


def _weighted(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """sum_w W_wc X_w / sum_w W_wc over the last axis of `values` (..., n_wl) -> (..., 3)."""
    return values @ weights / weights.sum(axis=0)


def gpu_clouds(clouds: Clouds, bottom_radius_m: float, wavelengths_nm: np.ndarray,
               sun_irradiance: np.ndarray, label: str = "") -> GpuClouds:
    """The viewer's arrays of `clouds` over a planet of radius `bottom_radius_m` [m], the
    optics on `wavelengths_nm` [nm] weighted by the star's `sun_irradiance` (n_wl,)
    [W m^-2 nm^-1] (module docstring); the clouds in their initial state (time 0, winds in
    the world axes: the page sets the wind's columns)."""
    field = cloud_field(clouds, bottom_radius_m, wavelengths_nm)
    extinction, albedo, asymmetry, phase = kernel_arrays(field)[3:7]
    weights = cmf_weights(field.wavelengths_nm) * np.asarray(sun_irradiance,
                                                             dtype=np.float64)[:, None]
    n = field.textures.shape[1]
    noise = np.empty((field.n_layers, n + 1, n, n, 2), dtype=np.float16)
    noise[:, :n] = field.textures
    noise[:, n] = field.textures[:, 0]
    header = {
        "label": label or clouds.name,
        "n_layers": int(field.n_layers),
        "texture_size": int(n),
        "bottom_radius_m": float(field.bottom_radius_m),
        "layer_names": [layer.name for layer in clouds.layers],
        "wind_enu_m_s": [[float(v) for v in layer.wind_m_s] for layer in clouds.layers],
        "mass_extinction_xyz_m2_g": _weighted(extinction, weights).tolist(),
        "single_scattering_albedo_xyz": _weighted(albedo, weights).tolist(),
        "asymmetry_xyz": _weighted(asymmetry, weights).tolist(),
        "ground_shade_xyz": _weighted(ground_shade(field), weights).tolist(),
    }
    arrays = {
        "noise": noise.reshape(field.n_layers * (n + 1), n, n, 2),
        "params": field.params.astype(np.float32),
        "profiles": field.profiles.astype(np.float32),
        "phase": _weighted(phase, weights).astype(np.float32),
    }
    return GpuClouds(header, arrays)


def encode_clouds(gpu: GpuClouds) -> bytes:
    """The binary message of `gpu` (module docstring)."""
    return pack_message((CLOUD_MAGIC, CLOUD_FORMAT_VERSION), gpu.header, gpu.arrays)


def decode_clouds(message: bytes) -> GpuClouds:
    """Inverse of `encode_clouds` (for tests and tools; the viewer decodes in JavaScript)."""
    return GpuClouds(*unpack_message(message, (CLOUD_MAGIC, CLOUD_FORMAT_VERSION), "cloud"))
