"""Colorimetry: spectra on a wavelength grid -> CIE XYZ -> RGB, white balance, transfer curves.

- XYZ: CIE 1931 2° colour-matching functions (CIE 015:2018, as tabulated at 1 nm, 360–830 nm, by
  colour-science; shipped in `data/colour_cie.npz`) integrated exactly over each
  grid cell (`grid.cell_edges`), times K_m = 683.002 lm W⁻¹. A spectrum on the grid is read as
  piecewise constant over its cells, so the weights are exact for it; XYZ is absolute (Y in cd m⁻²
  for radiance in W m⁻² sr⁻¹ nm⁻¹, in lx for irradiance in W m⁻² nm⁻¹).
- RGB: linear sRGB / Rec. 709, Display P3, Rec. 2020, ACEScg (AP1), ACES2065-1 (AP0); matrices
  derived from each space's primaries and white (SMPTE RP 177-1993 normalised primary matrix,
  colour-science data), computed once. XYZ is taken to be seen under a D65 white: spaces with
  another white (ACES ≈ D60) get a Bradford adaptation from D65 first, so D65 white -> R = G = B.
- Chromatic adaptation (von Kries-type, Bradford cone matrix, Lam 1985), white balance to a light
  source, CIE xy chromaticity, correlated colour temperature (McCamy 1992), and the sRGB transfer
  function (IEC 61966-2-1:1999).

The tables (colour-matching functions, illuminants, adaptation matrices, RGB primaries) come
from colour-science's datasets, copied into `data/colour_cie.npz` by
`scripts/make_data/colour_tables.py` (data/PROVENANCE.md), so rendering does not import
colour-science (1-2 s); results are cached per grid.

Public names: `LUMINOUS_EFFICACY_LM_PER_W`, `RGB_SPACES`, `CHROMATIC_ADAPTATION_METHODS`,
`cmf_weights`, `spectral_to_xyz`, `luminance`, `xyz_to_rgb`, `rgb_to_xyz`, `white_point_xyz`,
`normalised_primary_matrix`, `illuminant_spectrum`,
`chromatic_adaptation`, `white_balance`, `encode_srgb_transfer`, `decode_srgb_transfer`,
`xy_chromaticity`, `cct_mccamy_1992`.
"""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.grid import cell_average, cell_widths, checked_grid

__all__ = [
    "CHROMATIC_ADAPTATION_METHODS",
    "LUMINOUS_EFFICACY_LM_PER_W",
    "RGB_SPACES",
    "cct_mccamy_1992",
    "chromatic_adaptation",
    "cmf_weights",
    "decode_srgb_transfer",
    "encode_srgb_transfer",
    "illuminant_spectrum",
    "into_gamut",
    "normalised_primary_matrix",
    "luminance",
    "rgb_space_chromaticities",
    "rgb_to_xyz",
    "spectral_to_xyz",
    "white_balance",
    "white_point_xyz",
    "xy_chromaticity",
    "xyz_to_rgb",
]

# lm W⁻¹; maximum luminous efficacy of photopic vision at 555 nm (CIE 015:2018; follows from the
# SI candela definition, 683 lm W⁻¹ at 540 THz exactly).
LUMINOUS_EFFICACY_LM_PER_W = 683.002

COLOUR_DATA_FILE = "colour_cie.npz"  # in skyscatter/data; see data/PROVENANCE.md

# our name -> colour-science RGB_COLOURSPACES name
RGB_SPACES = {
    "srgb": "sRGB",  # IEC 61966-2-1, D65; same primaries as Rec. 709
    "rec709": "ITU-R BT.709",  # ITU-R BT.709-6, D65
    "display-p3": "Display P3",  # DCI-P3 primaries, D65
    "rec2020": "ITU-R BT.2020",  # ITU-R BT.2020-2, D65
    "acescg": "ACEScg",  # AP1 primaries, ACES white (≈ D60), SMPTE S-2014-004 / Academy S-2014-004
    "aces2065-1": "ACES2065-1",  # AP0 primaries, ACES white, SMPTE ST 2065-1
}

# our name -> colour-science CHROMATIC_ADAPTATION_TRANSFORMS name (cone-response matrices)
CHROMATIC_ADAPTATION_METHODS = {
    "bradford": "Bradford",  # Lam (1985), linearised as in CIECAM97s / ICC
    "cat02": "CAT02",  # CIECAM02, Moroney et al. (2002)
    "cat16": "CAT16",  # Li et al. (2017), Color Res. Appl. 42, 703
    "von-kries": "Von Kries",  # Hunt–Pointer–Estévez cone fundamentals
    "xyz-scaling": "XYZ Scaling",  # identity: scale X, Y, Z
}

_SRGB_LINEAR_LIMIT = 0.0031308  # IEC 61966-2-1:1999, breakpoint of the linear segment (linear)
_SRGB_ENCODED_LIMIT = 0.04045  # same breakpoint, encoded side


@lru_cache(maxsize=1)
def _tables() -> dict[str, np.ndarray]:
    """The arrays of `data/colour_cie.npz` (module docstring), read once."""
    path = resources.files("skyscatter").joinpath("data", COLOUR_DATA_FILE)
    with path.open("rb") as file, np.load(file, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


@lru_cache(maxsize=1)
def _cie1931_table() -> tuple[np.ndarray, np.ndarray]:
    """CIE 1931 2° x̄, ȳ, z̄ at 1 nm, 360–830 nm: (wavelength (471,), values (3, 471))."""
    tables = _tables()
    return tables["cmf_wavelengths_nm"], tables["cmf_xyz_bar"]


@lru_cache(maxsize=64)
def _cmf_weights_cached(grid: tuple[float, ...]) -> np.ndarray:
    wl = np.array(grid)
    table_wl, table_cmf = _cie1931_table()
    weights = LUMINOUS_EFFICACY_LM_PER_W * (cell_average(table_wl, table_cmf, wl)
                                            * cell_widths(wl)).T
    weights = np.ascontiguousarray(weights)
    weights.flags.writeable = False
    return weights


def cmf_weights(wavelengths_nm: ArrayLike) -> np.ndarray:
    r"""Weights W (n_wl, 3) with XYZ = spectrum @ W, absolute (Y = luminance).

        W_{j,c} = K_m ∫_{e_j}^{e_{j+1}} c̄(λ) dλ,   c̄ ∈ {x̄, ȳ, z̄},  K_m = 683.002 lm W⁻¹

    CIE 1931 2° standard observer (CIE 015:2018, 1 nm table 360–830 nm from colour-science),
    read as piecewise linear between the tabulated nanometres and 0 outside 360–830 nm,
    integrated exactly over the cells e_j of `grid.cell_edges`. Exact for a spectrum that is
    constant over each cell; on a 1 nm grid it equals the CIE 1 nm summation to < 0.1 %.
    Cached per grid (the array returned is read-only and shared).

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid, strictly ascending. [nm]

    Returns
    -------
    ndarray, shape (n_wl, 3)
        Weights. [lm W⁻¹ nm] (cd m⁻² per W m⁻² sr⁻¹ nm⁻¹ of spectral radiance)
    """
    return _cmf_weights_cached(tuple(checked_grid(wavelengths_nm).tolist()))


def spectral_to_xyz(spectral: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
    """Absolute CIE 1931 XYZ of spectra on a grid: `spectral @ cmf_weights(wavelengths_nm)`.

    Parameters
    ----------
    spectral : array_like, shape (..., n_wl)
        Spectral radiance [W m⁻² sr⁻¹ nm⁻¹] (or spectral irradiance [W m⁻² nm⁻¹]).
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid of the last axis. [nm]

    Returns
    -------
    ndarray, shape (..., 3)
        X, Y, Z; Y is luminance [cd m⁻²] (or illuminance [lx]). float32 for float32 input,
        float64 otherwise.
    """
    weights = cmf_weights(wavelengths_nm)
    s = np.asarray(spectral)
    if not np.issubdtype(s.dtype, np.floating):
        s = s.astype(np.float64)
    if s.ndim == 0 or s.shape[-1] != weights.shape[0]:
        raise InputError(
            f"spectral must have the {weights.shape[0]} grid wavelengths on its last axis; "
            f"got shape {s.shape}", key="spectral", value=s.shape,
            allowed=f"shape (..., {weights.shape[0]})")
    if s.dtype == np.float32:  # keep float32 images float32 (no 2x upcast copy)
        weights = weights.astype(np.float32)
    return s @ weights


def luminance(spectral: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
    """Luminance Y = K_m ∫ L(λ) ȳ(λ) dλ of spectra on a grid (CIE 1931 2°, see `cmf_weights`).

    Parameters
    ----------
    spectral : array_like, shape (..., n_wl)
        Spectral radiance [W m⁻² sr⁻¹ nm⁻¹] (or spectral irradiance [W m⁻² nm⁻¹]).
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid of the last axis. [nm]

    Returns
    -------
    ndarray, shape (...)
        Luminance [cd m⁻²] (or illuminance [lx]).
    """
    return spectral_to_xyz(spectral, wavelengths_nm)[..., 1]


def _lookup(table: dict[str, str], name: str, what: str) -> str:
    key = str(name).lower()
    if key not in table:
        raise InputError(f"unknown {what} {name!r}; allowed: {', '.join(table)}", key=what,
                         value=name, allowed=", ".join(table))
    return table[key]


@lru_cache(maxsize=1)
def _illuminant_names() -> dict[str, str]:
    return {str(name).lower(): str(name) for name in _tables()["illuminant_names"]}


def illuminant_spectrum(name: str, wavelengths_nm: ArrayLike) -> np.ndarray:
    """Relative spectral power of the CIE illuminant D65, D50 or A (CIE 015:2018, as tabulated
    by colour-science `SDS_ILLUMINANTS`) at `wavelengths_nm`, linear between its tabulated
    values. [-]"""
    tables = _tables()
    shipped = {key[4:].lower(): key[4:] for key in tables
               if key.startswith("spd_") and not key.endswith("_wavelengths_nm")}
    key = _lookup(shipped, name, "illuminant")
    return np.interp(np.asarray(wavelengths_nm, dtype=np.float64),
                     tables[f"spd_{key}_wavelengths_nm"], tables[f"spd_{key}"])


def white_point_xyz(white: str | ArrayLike) -> np.ndarray:
    """XYZ of a white normalised to Y = 1, from a CIE illuminant name or an XYZ triple.

    Names are those of colour-science `CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]`
    (case-insensitive: "D65" = (0.3127, 0.3290), "D50", "A", "E", "ACES", ...; CIE 015:2018).

    Parameters
    ----------
    white : str or array_like, shape (..., 3)
        Illuminant name, or XYZ with Y > 0 (any scale).

    Returns
    -------
    ndarray, shape (3,) or (..., 3)
        White XYZ with Y = 1. [-]
    """
    if isinstance(white, str):
        name = _lookup(_illuminant_names(), white, "white")
        tables = _tables()
        x, y = tables["illuminant_xy"][list(tables["illuminant_names"]).index(name)]
        return np.array([x / y, 1.0, (1.0 - x - y) / y])
    xyz = _checked_xyz(white, "white")
    bad = ~(xyz[..., 1] > 0.0)
    if np.any(bad):
        first = xyz[tuple(np.argwhere(bad)[0])] if xyz.ndim > 1 else xyz
        raise InputError(f"a white must have Y > 0; got XYZ {first.ravel().tolist()!r}",
                         key="white", value=first.ravel().tolist(), allowed="Y > 0")
    return xyz / xyz[..., 1:2]


@lru_cache(maxsize=16)
def _cone_matrix(method: str) -> np.ndarray:
    _lookup(CHROMATIC_ADAPTATION_METHODS, method, "chromatic adaptation method")
    tables = _tables()
    index = list(tables["adaptation_names"]).index(str(method).lower())
    m = np.array(tables["adaptation_matrices"][index], dtype=np.float64)
    m.flags.writeable = False
    return m


def chromatic_adaptation(xyz: ArrayLike, source_white_xyz: ArrayLike,
                         target_white: str | ArrayLike = "D65",
                         method: str = "bradford") -> np.ndarray:
    r"""Von Kries-type chromatic adaptation from a source white to a target white.

        XYZ' = M⁻¹ diag(ρ_t / ρ_s) M XYZ,   ρ = M XYZ_white (whites scaled to Y = 1)

    von Kries (1902) scaling in a cone-like space; M = Bradford matrix by default (Lam 1985,
    PhD thesis, Univ. of Bradford; linearised form of CIECAM97s, as in ICC profiles), other
    matrices from `CHROMATIC_ADAPTATION_METHODS` (colour-science data). Both whites are scaled to
    Y = 1, so only their chromaticity matters: the source white maps to the target white's
    chromaticity at its own luminance.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        Colours to adapt. [any XYZ unit]
    source_white_xyz : array_like, shape (..., 3)
        XYZ of the white under which `xyz` was seen (Y > 0; broadcasts with `xyz`).
    target_white : str or array_like, shape (..., 3)
        Illuminant name ("D65", "D50", "E", ...) or XYZ of the white to adapt to.
    method : str
        One of `CHROMATIC_ADAPTATION_METHODS`: "bradford", "cat02", "cat16", "von-kries",
        "xyz-scaling".

    Returns
    -------
    ndarray, shape broadcast(...) + (3,)
        Adapted XYZ, same unit as `xyz`.
    """
    m = _cone_matrix(method)
    colours = _checked_xyz(xyz, "xyz")
    source = white_point_xyz(source_white_xyz)
    target = white_point_xyz(target_white)
    gain = (target @ m.T) / (source @ m.T)
    return ((colours @ m.T) * gain) @ np.linalg.inv(m).T


def white_balance(xyz: ArrayLike, light_spectrum: ArrayLike, wavelengths_nm: ArrayLike,
                  target_white: str | ArrayLike = "D65", method: str = "bradford") -> np.ndarray:
    """Adapt XYZ seen under a light source to a target white (default D65), like a camera's white
    balance: `chromatic_adaptation(xyz, spectral_to_xyz(light_spectrum), target_white)`.

    The source white is the XYZ of `light_spectrum` (e.g. the sunlight transmitted to the ground);
    Bradford von Kries adaptation (Lam 1985) as in `chromatic_adaptation`.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        Colours to adapt. [any XYZ unit]
    light_spectrum : array_like, shape (..., n_wl)
        Spectrum of the light source; broadcasts with `xyz`'s leading axes. [any spectral unit]
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid of `light_spectrum`. [nm]
    target_white, method :
        As in `chromatic_adaptation`.

    Returns
    -------
    ndarray, shape broadcast(...) + (3,)
        Adapted XYZ.
    """
    source = spectral_to_xyz(light_spectrum, wavelengths_nm)
    return chromatic_adaptation(xyz, source, target_white, method)


def normalised_primary_matrix(primaries_xy: ArrayLike, white_xy: ArrayLike) -> np.ndarray:
    """RGB -> XYZ matrix of an RGB space from its primaries' and white's xy chromaticities.

        P = [X_r X_g X_b; 1 1 1; Z_r Z_g Z_b] (each primary at Y = 1),  S = P⁻¹ W,
        NPM = P diag(S)

    with W the white's XYZ at Y = 1, so RGB = (1, 1, 1) is the white (SMPTE RP 177-1993, eqs.
    3.1-3.4).

    Parameters
    ----------
    primaries_xy : array_like, shape (3, 2)
        xy of the red, green and blue primaries. [-]
    white_xy : array_like, shape (2,)
        xy of the white. [-]

    Returns
    -------
    ndarray, shape (3, 3)
        NPM: XYZ = NPM @ RGB. [-]
    """
    xy = np.asarray(primaries_xy, dtype=np.float64)
    x, y = xy[:, 0], xy[:, 1]
    p = np.stack([x / y, np.ones(3), (1.0 - x - y) / y])
    wx, wy = np.asarray(white_xy, dtype=np.float64)
    white = np.array([wx / wy, 1.0, (1.0 - wx - wy) / wy])
    return p * np.linalg.solve(p, white)


def _space_primaries(space: str) -> tuple[np.ndarray, np.ndarray]:
    """(primaries (3, 2), white (2,)) CIE xy of one of `RGB_SPACES` (from colour-science)."""
    _lookup(RGB_SPACES, space, "colour space")
    tables = _tables()
    index = list(tables["rgb_names"]).index(str(space).lower())
    return tables["rgb_primaries_xy"][index], tables["rgb_white_xy"][index]


def rgb_space_chromaticities(space: str) -> tuple[float, ...]:
    """CIE xy of the red, green and blue primaries and the white of one of `RGB_SPACES`,
    (x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w): an OpenEXR `chromaticities` attribute."""
    primaries, white = _space_primaries(space)
    return tuple(float(v) for v in (*np.ravel(primaries), *white))


@lru_cache(maxsize=16)
def _xyz_to_rgb_matrix(space: str) -> np.ndarray:
    primaries, white = _space_primaries(space)
    matrix = np.linalg.inv(normalised_primary_matrix(primaries, white))
    d65 = white_point_xyz("D65")
    x, y = white
    space_white = np.array([x / y, 1.0, (1.0 - x - y) / y])
    if not np.allclose(space_white, d65, rtol=0.0, atol=1e-12):
        m = _cone_matrix("bradford")
        cat = np.linalg.inv(m) @ np.diag((space_white @ m.T) / (d65 @ m.T)) @ m
        matrix = matrix @ cat
    matrix.flags.writeable = False
    return matrix


def xyz_to_rgb(xyz: ArrayLike, space: str = "srgb") -> np.ndarray:
    """Linear RGB of XYZ seen under D65, in one of `RGB_SPACES`.

        RGB = N⁻¹ C XYZ

    N: normalised primary matrix of the space (SMPTE RP 177-1993, from its primaries and white
    point in colour-science), so the space's white at Y = 1 gives R = G = B = 1. C: identity for
    the D65 spaces (srgb, rec709, display-p3, rec2020); Bradford adaptation (Lam 1985) from D65 to
    the ACES white (x, y) = (0.32168, 0.33767) for "acescg" (AP1) and "aces2065-1" (AP0), the usual
    choice when putting D65 renders into ACES. No clipping, no transfer curve (see
    `encode_srgb_transfer`).

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        CIE XYZ. [any unit; RGB comes out in the same unit]
    space : str
        "srgb", "rec709", "display-p3", "rec2020", "acescg" or "aces2065-1".

    Returns
    -------
    ndarray, shape (..., 3)
        Linear R, G, B.
    """
    matrix = _xyz_to_rgb_matrix(space)
    return _checked_xyz(xyz, "xyz") @ matrix.T


def into_gamut(rgb: ArrayLike, space: str = "srgb") -> np.ndarray:
    """Linear RGB (..., 3) of `space` with the colours outside its gamut brought inside at
    constant luminance: rgb' = Y + k (rgb - Y), Y the colour's luminance (the white (1, 1, 1)
    has luminance 1), k in [0, 1] the largest that leaves no channel below 0 (desaturation
    towards the white, hue kept). Colours inside, and the luminance of all, are unchanged;
    a colour of luminance <= 0 becomes black. For light a renderer integrates (image-based
    lighting): a negative channel, e.g. a setting sun's blue in sRGB, is not light."""
    rgb = np.asarray(rgb, dtype=np.float64)
    y = rgb_to_xyz(rgb, space)[..., 1:2]
    low = np.min(rgb, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.clip(y / (y - low), 0.0, 1.0)
    inside = np.where(y > 0.0, y + k * (rgb - y), 0.0)
    return np.where(low < 0.0, inside, rgb)


def rgb_to_xyz(rgb: ArrayLike, space: str = "srgb") -> np.ndarray:
    """Inverse of `xyz_to_rgb`: XYZ (seen under D65) of linear RGB in `space`, shape (..., 3)."""
    matrix = np.linalg.inv(_xyz_to_rgb_matrix(space))
    return _checked_xyz(rgb, "rgb") @ matrix.T


def encode_srgb_transfer(linear: ArrayLike) -> np.ndarray:
    """sRGB transfer function (OETF / inverse EOTF), linear -> encoded.

        V = 12.92 L                    for L <= 0.0031308
        V = 1.055 L^(1/2.4) - 0.055    otherwise

    IEC 61966-2-1:1999 (sRGB), encoding. Extended to negative values by odd symmetry
    (V(-L) = -V(L)), as in scRGB; values above 1 are not clipped.

    Parameters
    ----------
    linear : array_like, any shape
        Linear values, 1 = white. [-]

    Returns
    -------
    ndarray, same shape
        Encoded values. [-]
    """
    x = np.asarray(linear, dtype=np.float64)
    a = np.abs(x)
    with np.errstate(invalid="ignore"):
        curve = 1.055 * np.power(a, 1.0 / 2.4) - 0.055
    return np.sign(x) * np.where(a <= _SRGB_LINEAR_LIMIT, 12.92 * a, curve)


def decode_srgb_transfer(encoded: ArrayLike) -> np.ndarray:
    """Inverse of `encode_srgb_transfer` (sRGB EOTF), encoded -> linear.

        L = V / 12.92                    for V <= 0.04045
        L = ((V + 0.055) / 1.055)^2.4    otherwise

    IEC 61966-2-1:1999 (sRGB), decoding; odd symmetry for negative values.

    Parameters
    ----------
    encoded : array_like, any shape
        Encoded values. [-]

    Returns
    -------
    ndarray, same shape
        Linear values. [-]
    """
    v = np.asarray(encoded, dtype=np.float64)
    a = np.abs(v)
    return np.sign(v) * np.where(a <= _SRGB_ENCODED_LIMIT, a / 12.92,
                                 ((a + 0.055) / 1.055) ** 2.4)


def xy_chromaticity(xyz: ArrayLike) -> np.ndarray:
    """CIE 1931 chromaticity x = X/(X+Y+Z), y = Y/(X+Y+Z) (CIE 015:2018, §7).

    Black (X + Y + Z = 0) gets the D65 white point (0.3127, 0.3290), so images stay finite.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        CIE XYZ. [any unit]

    Returns
    -------
    ndarray, shape (..., 2)
        x, y. [-]
    """
    v = _checked_xyz(xyz, "xyz")
    total = v.sum(axis=-1, keepdims=True)
    black = total == 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        xy = v[..., :2] / np.where(black, 1.0, total)
    return np.where(black, np.array([0.3127, 0.3290]), xy)


def cct_mccamy_1992(xy: ArrayLike) -> np.ndarray:
    """Correlated colour temperature from CIE 1931 chromaticity (McCamy's cubic).

        n = (x - 0.3320) / (0.1858 - y)
        CCT = 449 n³ + 3525 n² + 6823.3 n + 5520.33

    McCamy (1992), Color Res. Appl. 17, 142, doi:10.1002/col.5080170211 (erratum 18, 150).
    Within ≈ 2 K of the Robertson method for 2856–6504 K and a few tens of K up to ~10 000 K;
    meaningless far from the Planckian locus or outside ≈ 2000–12 500 K. D65 -> 6504 K.

    Parameters
    ----------
    xy : array_like, shape (..., 2)
        Chromaticity x, y. [-]

    Returns
    -------
    ndarray, shape (...)
        Correlated colour temperature. [K]
    """
    c = np.asarray(xy, dtype=np.float64)
    if c.ndim == 0 or c.shape[-1] != 2:
        raise InputError(f"xy must have shape (..., 2); got {c.shape}", key="xy", value=c.shape,
                         allowed="shape (..., 2)")
    n = (c[..., 0] - 0.3320) / (0.1858 - c[..., 1])
    return ((449.0 * n + 3525.0) * n + 6823.3) * n + 5520.33


def _checked_xyz(value: ArrayLike, name: str) -> np.ndarray:
    v = np.asarray(value)
    if not np.issubdtype(v.dtype, np.floating):
        try:
            v = v.astype(np.float64)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{name} must be numbers; got {value!r}", key=name, value=value,
                             allowed="shape (..., 3)") from exc
    if v.ndim == 0 or v.shape[-1] != 3:
        raise InputError(f"{name} must have 3 components on its last axis; got shape {v.shape}",
                         key=name, value=v.shape, allowed="shape (..., 3)")
    return v
