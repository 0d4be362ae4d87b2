r"""The compact description of an atmosphere from which the viewer computes Hillaire's fast
model on the GPU (S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering
Technique", Computer Graphics Forum 39(4), EGSR 2020, doi:10.1111/cgf.14050): the optical
profile itself, not tables, so that the page can change a constituent's amount or the ground
albedo and draw the result in the next frame (docs/viewer.md, "Instant changes").

Spectral, not RGB: the page computes the model on FAST_WAVELENGTH_BINS wavelengths, four to a
pass (one RGBA texel holds four wavelengths: FAST_GROUP), and turns the radiance into CIE XYZ
at the end with the weights C_wc E_w (`cmf_weights` times the star's irradiance: the LUTs are
computed for a unit irradiance, as Hillaire's), the same exact linear conversion
`gpu_tables` applies to the spectral tables. Three channels would have to average products of
spectra (sigma_s T with T = exp(-tau)), which is not exact; four wavelengths a pass cost the
GPU two passes per table instead of one.

Message layout (`encode_fast`, read by `gpu_tables.unpack_message`): b"SKYF", version, JSON
header, then float32 arrays:
  density   (n_c * rows, PHASE_ROW)     each constituent's density over the uniform altitudes
                                        0 .. top (header "altitude_step_m", "altitudes" levels),
                                        divided by its largest value ("density_scale"); level i
                                        of constituent c at (i % PHASE_ROW, c * rows +
                                        i // PHASE_ROW) ("density_rows": a fog's 13 335 levels
                                        fit in a texture this way)
  phase     (n_c * n_g, PHASE_ROW, 4)   p_c(theta_i), theta_i = pi i / (PHASE_ROW - 1), of
                                        constituent c at the four wavelengths of group g in
                                        row c * n_g + g (zeros for a constituent that does not
                                        scatter) [sr^-1]
Header: radii, the sun zenith cosine around which the multiple-scattering LUT's columns crowd
("multiple_scattering_mu_s_centre", `hillaire.multiple_scattering_sun_centre`), the
wavelengths, per constituent its name and extinction and scattering coefficients at the largest
density [m^-1] (n_c, n_wl), the ground albedo (n_wl), the star's irradiance (n_wl)
[W m^-2 nm^-1], the XYZ weights (n_wl, 3) and the star as the tables' header has it
(`gpu_tables.sun_header`).
"""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere.model import Atmosphere, OpticalProfile
from skyscatter.spectrum.colour import cmf_weights
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.hillaire import (
    MULTIPLE_SCATTERING_SIZE,
    multiple_scattering_sun_centre,
)
from skyscatter.viewer.gpu_tables import PHASE_ROW, pack_message, sun_header, unpack_message

__all__ = ["FAST_FORMAT_VERSION", "FAST_GROUP", "FAST_IRRADIANCE_DIRECTIONS", "FAST_MAGIC",
           "FAST_SIZES", "FAST_STEPS", "FAST_WAVELENGTH_BINS", "MAX_CONSTITUENTS", "MAX_GROUPS",
           "decode_fast", "encode_fast", "fast_description", "fast_profile"]

FAST_MAGIC = b"SKYF"
FAST_FORMAT_VERSION = 1
FAST_WAVELENGTH_BINS = 8  # those of the preview tables (viewer.table_service.QUALITIES)
FAST_GROUP = 4  # wavelengths per RGBA texel: one pass of each LUT per group
MAX_CONSTITUENTS = 8  # the shader's uniform arrays
MAX_GROUPS = 4  # wavelength groups the page converts to XYZ (16 wavelengths)
# The LUTs' sizes (width, height) and the samples of their ray marches, Hillaire's (the
# multiple scattering's nodes and directions those of the CPU solver's table,
# transport.hillaire), and the sky's irradiance on the ground over the sun's cosine, ours
# (fast_model.glsl), from the sky on FAST_IRRADIANCE_DIRECTIONS directions
FAST_SIZES = {"transmittance": (256, 64), "multiple": MULTIPLE_SCATTERING_SIZE[::-1],
              "irradiance": (32, 1), "sky_view": (192, 108)}
FAST_STEPS = {"transmittance": 40, "multiple": 20, "sky_view": 32}
FAST_IRRADIANCE_DIRECTIONS = 64


def fast_profile(atmosphere: Atmosphere) -> OpticalProfile:
    """The optical profile the fast model is described from: FAST_WAVELENGTH_BINS bins."""
    return atmosphere.optical_profile(wavelength_grid(FAST_WAVELENGTH_BINS))


def fast_description(atmosphere: Atmosphere, profile: OpticalProfile,
                     label: str = "") -> tuple[dict, dict[str, np.ndarray]]:
    """(header, arrays) of the fast model's message for `profile` (of `atmosphere`)."""
    n_c, n_wl = profile.extinction_per_density.shape
    if n_wl % FAST_GROUP:
        raise ValueError(f"the fast model takes wavelengths in groups of {FAST_GROUP}")
    if n_wl > FAST_GROUP * MAX_GROUPS:
        raise ValueError(f"the fast model takes at most {FAST_GROUP * MAX_GROUPS} wavelengths")
    if n_c > MAX_CONSTITUENTS:
        raise ValueError(f"the fast model takes at most {MAX_CONSTITUENTS} constituents")
    groups = n_wl // FAST_GROUP
    scale = np.max(profile.density, axis=1)
    scale = np.where(scale > 0.0, scale, 1.0)
    n_z = profile.density.shape[1]
    rows = -(-n_z // PHASE_ROW)
    density = np.zeros((n_c, rows * PHASE_ROW), dtype=np.float32)
    density[:, :n_z] = profile.density / scale[:, None]
    nu = np.cos(np.linspace(0.0, np.pi, PHASE_ROW))
    phase = np.zeros((n_c, groups, PHASE_ROW, FAST_GROUP), dtype=np.float32)
    for c, function in enumerate(profile.phases):
        if function is not None:
            values = function.evaluate(nu, profile.wavelengths_nm)  # (PHASE_ROW, n_wl)
            phase[c] = values.reshape(PHASE_ROW, groups, FAST_GROUP).transpose(1, 0, 2)
    weights = cmf_weights(profile.wavelengths_nm)
    header = {
        "label": label,
        "bottom_radius_m": float(profile.bottom_radius_m),
        "top_radius_m": float(profile.top_radius_m),
        "multiple_scattering_mu_s_centre": multiple_scattering_sun_centre(
            profile.bottom_radius_m, profile.top_radius_m),
        "altitude_step_m": float(profile.altitudes_m[1] - profile.altitudes_m[0]),
        "altitudes": int(n_z),
        "density_rows": int(rows),
        "wavelengths_nm": [float(v) for v in profile.wavelengths_nm],
        "groups": groups,
        "names": list(profile.names),
        "density_scale": [float(v) for v in scale],
        "extinction_m": (profile.extinction_per_density * scale[:, None]).tolist(),
        "scattering_m": (profile.scattering_per_density * scale[:, None]).tolist(),
        "ground_albedo": [float(v) for v in profile.ground_albedo],
        "sun_irradiance": [float(v) for v in profile.toa_irradiance],
        "xyz_weights": weights.tolist(),
        **sun_header(profile, atmosphere.planet.star, weights),
    }
    return header, {"density": density.reshape(n_c * rows, PHASE_ROW),
                    "phase": phase.reshape(n_c * groups, PHASE_ROW, FAST_GROUP)}


def encode_fast(header: dict, arrays: dict[str, np.ndarray]) -> bytes:
    """The binary message (module docstring)."""
    return pack_message((FAST_MAGIC, FAST_FORMAT_VERSION), header, arrays)


def decode_fast(message: bytes) -> tuple[dict, dict[str, np.ndarray]]:
    """Inverse of `encode_fast` (for tests; the viewer decodes in JavaScript)."""
    return unpack_message(message, (FAST_MAGIC, FAST_FORMAT_VERSION), "fast model")
