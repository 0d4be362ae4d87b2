"""Exposure, tone mapping and 8-bit sRGB encoding of linear RGB images.

The chain is: linear RGB in absolute units (luminance Y in cd m⁻²)
  × `exposure_scale(ev100)` (photographic exposure: 1 at the sensor's clipping level)
  → `tonemap(..., operator)` (compress [0, ∞) into display-linear [0, 1])
  → `to_srgb8` (sRGB transfer function, 8-bit quantisation).

Sources:

* Exposure from EV100, saturation-based sensitivity: L_max = 78 / (q S) · N² / t with lens
  and vignetting factor q = 0.65 and S = 100 ISO, so L_max = 1.2 · 2^EV100 [cd m⁻²] and the
  exposure scale is 1 / L_max. Lagarde & de Rousiers (2014), "Moving Frostbite to Physically
  Based Rendering 3.0", SIGGRAPH course notes, section on the physically based camera;
  ISO 12232 (saturation-based speed).
* Automatic exposure: a reflected-light meter sets N² / t = L S / K with calibration constant
  K = 12.5 cd s m⁻² (ISO 2720:1974 allows 10.6–13.4; 12.5 is the usual maker's choice), so
  EV100 = log2(L_avg · 100 / 12.5). The metered scene luminance then lands at
  K q / 78 = 12.5 · 0.65 / 78 = 1/9.6 ≈ 0.104 of the clipping level.
  L_avg is the log-average (geometric mean) luminance of Reinhard et al. (2002), "Photographic
  tone reproduction for digital images", ACM TOG 21(3), 267, eq. 1, doi:10.1145/566654.566575;
  departure: pixels with zero luminance are left out instead of adding a small δ, so the
  result does not depend on δ.
* Night adaptation (`night_compensation_ev`): the key value of Krawczyk, Myszkowski & Seidel
  (2005), "Lightness perception in tone reproduction for high dynamic range images", Computer
  Graphics Forum 24(3), 635 (the automatic key value), doi:10.1111/j.1467-8659.2005.00888.x:
  α(L̄) = 1.03 − 2 / (2 + log10(L̄ + 1)), L̄ the log-average luminance [cd m⁻²]. Dim scenes get a
  lower key, so night looks dark instead of being metered up to a daylight grey. We apply it
  relative to a daylight sky (L̄ = 3000 cd m⁻², α = 0.665): log2(α(L̄) / α(3000)) stops, 0 by
  day, −0.8 at 30 cd m⁻², held at −1.79 below about 12 cd m⁻² (civil twilight and night):
  there the metered log-average lands at 0.03 of the clipping level instead of 1/9.6, the key
  Krawczyk's formula gives a dark scene (α → 0.03 as L̄ → 0). Its full drop relative to a
  daylight key (−4.5 stops) left moonlit skies nearly black on a display. Sky pixels below the
  luminance of the natural moonless night sky, 22.0 mag arcsec⁻² in V (Falchi et al. 2016,
  "The new world atlas of artificial night sky brightness", Sci. Adv. 2, e1600377,
  doi:10.1126/sciadv.1600377: 174 µcd m⁻²), are metered as that luminance, so a black sky
  with a few stars meters as night.
* Operators: `exponential` 1 − exp(−x) (Bruneton 2017, precomputed_atmospheric_scattering demo,
  without its 1/2.2 gamma); `aces` x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14) clipped to
  [0, 1] (Narkowicz 2016, "ACES Filmic Tone Mapping Curve", blog post of 2016-01-06, a fit to
  the ACES RRT + Rec.709 ODT); `reinhard` x / (1 + x) (Reinhard et al. 2002, eq. 3);
  `clamp` min(x, 1).
* sRGB transfer function (OETF): V = 12.92 L for L ≤ 0.0031308, else 1.055 L^(1/2.4) − 0.055
  (IEC 61966-2-1:1999, sRGB encoding); 8-bit code = round(255 V).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.colour import decode_srgb_transfer

__all__ = [
    "OPERATORS",
    "adapted_ev100",
    "METER_CALIBRATION_K",
    "NATURAL_NIGHT_SKY_CD_M2",
    "aces_narkowicz2016",
    "auto_ev100",
    "night_adapted_exposure",
    "night_compensation_ev",
    "clamp",
    "exponential",
    "exposure_scale",
    "reinhard",
    "to_srgb8",
    "tonemap",
]

METER_CALIBRATION_K = 12.5  # cd s m⁻², reflected-light meter calibration constant (ISO 2720)
INCIDENT_CALIBRATION_C = 250.0  # lx s, incident-light meter, flat receptor (ISO 2720: 240-400)
_ISO_SPEED = 100.0  # EV100 is defined for ISO 100
NATURAL_NIGHT_SKY_CD_M2 = 174e-6  # cd m⁻², 22.0 mag arcsec⁻² V (Falchi et al. 2016)
_DARK_SCENE_KEY = 0.03  # Krawczyk et al. (2005): their key value as L̄ -> 0
_DAYLIGHT_LOG_AVERAGE_CD_M2 = 3000.0  # cd m⁻², where night_compensation_ev is 0
_SATURATION_FACTOR = 78.0 / (0.65 * _ISO_SPEED)  # = 1.2; 78/(q S), q = 0.65 (Lagarde 2014)
_LARGEST_INPUT = 1e150  # inputs are clipped here so x² stays finite in float64


def exposure_scale(ev100: float, compensation_ev: float = 0.0) -> float:
    """Factor that takes luminance [cd m⁻²] to exposure relative to clipping [-].

    scale = 2^compensation / (1.2 · 2^EV100)   (Lagarde & de Rousiers 2014)

    Parameters
    ----------
    ev100 : float
        Exposure value at ISO 100; higher for brighter scenes (≈ 15 for a sunny day). [EV]
    compensation_ev : float
        Exposure compensation; +1 doubles the output (one stop brighter). [EV]
    """
    ev100 = float(ev100)
    compensation_ev = float(compensation_ev)
    if not (np.isfinite(ev100) and np.isfinite(compensation_ev)):
        raise InputError(f"ev100 = {ev100!r} and compensation_ev = {compensation_ev!r} must be "
                         "finite", key="ev100", value=ev100)
    return float(2.0 ** (compensation_ev - ev100) / _SATURATION_FACTOR)


def auto_ev100(luminance: ArrayLike, valid: ArrayLike | None = None) -> float:
    """EV100 a reflected-light meter would choose for the scene. [EV]

    EV100 = log2(L_avg · S / K), S = 100, K = 12.5 (ISO 2720), with L_avg the geometric mean
    of the finite, positive luminances where `valid` is True. With `exposure_scale`, a uniform
    scene of luminance L maps to 1/9.6 ≈ 0.104 whatever L is.

    Parameters
    ----------
    luminance : array_like, any shape
        Luminance, e.g. an image (h, w). [cd m⁻²]
    valid : array_like of bool, broadcastable to `luminance`, optional
        Pixels to meter (e.g. the fisheye circle); all pixels when None.
    """
    lum = np.asarray(luminance, dtype=np.float64)
    use = np.isfinite(lum) & (lum > 0.0)
    if valid is not None:
        use &= np.broadcast_to(np.asarray(valid, dtype=bool), lum.shape)
    if not np.any(use):
        raise InputError("cannot meter the exposure: no valid pixel has a positive luminance; "
                         "give an explicit EV100 instead", key="luminance")
    log_average = float(np.exp(np.mean(np.log(lum[use]))))
    return float(np.log2(log_average * _ISO_SPEED / METER_CALIBRATION_K))


def night_compensation_ev(log_average_luminance: float) -> float:
    """Exposure change [EV] for a scene of log-average luminance L̄ [cd m⁻²]:
    max(log2(α(L̄) / α(3000)), log2(0.03 · 9.6)), α(L) = 1.03 − 2 / (2 + log10(L + 1))
    (Krawczyk et al. 2005; module docstring). 0 for a daylight sky, −1.79 in twilight and at
    night."""
    def key(luminance: float) -> float:
        return 1.03 - 2.0 / (2.0 + np.log10(luminance + 1.0))

    if not (np.isfinite(log_average_luminance) and log_average_luminance >= 0.0):
        raise InputError(f"log-average luminance {log_average_luminance!r} must be finite and "
                         ">= 0 [cd m^-2]", key="luminance", value=log_average_luminance)
    shift = np.log2(key(log_average_luminance) / key(_DAYLIGHT_LOG_AVERAGE_CD_M2))
    metered_grey = METER_CALIBRATION_K / (_ISO_SPEED * _SATURATION_FACTOR)  # 1/9.6
    floor = np.log2(_DARK_SCENE_KEY / metered_grey)
    return float(max(shift, floor))


def night_adapted_exposure(luminance: ArrayLike, sky: ArrayLike) -> tuple[float, float]:
    """(EV100, night compensation [EV]) for an image by day or night: the reflected-light
    meter of `auto_ev100` over the `sky` pixels with every luminance held at least at the
    natural night sky's (`NATURAL_NIGHT_SKY_CD_M2`), and `night_compensation_ev` of that
    log-average luminance. [EV]"""
    lum = np.asarray(luminance, dtype=np.float64)
    floor = np.where(np.isfinite(lum), np.maximum(lum, NATURAL_NIGHT_SKY_CD_M2), np.nan)
    ev100 = auto_ev100(floor, sky)
    log_average = 2.0**ev100 * METER_CALIBRATION_K / _ISO_SPEED
    return ev100, night_compensation_ev(log_average)


def adapted_ev100(previous_ev100: float | None, metered_ev100: float, elapsed_s: float,
                  time_constant_s: float) -> float:
    """Exposure that follows the metered one smoothly in time, as an eye or an auto-exposure
    camera adapts: EV ← EV + (EV_metered − EV)(1 − exp(−Δt / τ)), a first-order low-pass in
    stops; the metered value itself when there is no previous one or τ = 0. [EV]"""
    if previous_ev100 is None or time_constant_s <= 0.0:
        return float(metered_ev100)
    weight = 1.0 - np.exp(-max(elapsed_s, 0.0) / time_constant_s)
    return float(previous_ev100 + (metered_ev100 - previous_ev100) * weight)


def incident_ev100(illuminance_lux: float) -> float:
    """EV100 an incident-light meter would choose under `illuminance_lux` [lx]: log2(E S / C),
    S = 100, C = 250 (ISO 2720, flat receptor). A white Lambertian surface facing the light
    then maps to 0.66 with `exposure_scale` (grey cards to middle grey), whatever else the
    frame holds: the choice for sunlit objects against black space. [EV]"""
    if not (np.isfinite(illuminance_lux) and illuminance_lux > 0.0):
        raise InputError(f"cannot meter the exposure: illuminance {illuminance_lux!r} lx is not "
                         "positive; give an explicit EV100 instead", key="illuminance_lux")
    return float(np.log2(illuminance_lux * _ISO_SPEED / INCIDENT_CALIBRATION_C))


def exponential(x: ArrayLike) -> np.ndarray:
    """1 − exp(−x) [-] (Bruneton 2017 demo); x ≥ 0 exposed linear values, same shape out."""
    return -np.expm1(-np.asarray(x, dtype=np.float64))


def aces_narkowicz2016(x: ArrayLike) -> np.ndarray:
    """Narkowicz (2016) fit of the ACES filmic curve, clipped to [0, 1] [-]; same shape out.

    f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14); f(0) = 0, f(1) ≈ 0.804,
    f(∞) = 2.51 / 2.43 > 1, hence the clip. Meant for x ≥ 0.
    """
    x = np.asarray(x, dtype=np.float64)
    return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def reinhard(x: ArrayLike) -> np.ndarray:
    """x / (1 + x) [-] (Reinhard et al. 2002, eq. 3); x ≥ 0, same shape out."""
    x = np.asarray(x, dtype=np.float64)
    return x / (1.0 + x)


def clamp(x: ArrayLike) -> np.ndarray:
    """Linear, clipped to [0, 1] [-]; same shape out."""
    return np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)


OPERATORS: dict[str, Callable[[ArrayLike], np.ndarray]] = {
    "aces": aces_narkowicz2016,
    "clamp": clamp,
    "exponential": exponential,
    "reinhard": reinhard,
}


def tonemap(linear_rgb: ArrayLike, operator: str = "aces", exposure: float = 1.0) -> np.ndarray:
    """Display-linear values in [0, 1] from exposed linear RGB, channel by channel.

    Parameters
    ----------
    linear_rgb : array_like, shape (..., 3) (any shape works)
        Linear RGB; usually luminance-scaled values times `exposure_scale(...)`. Negative
        values (colours outside the RGB gamut) are clipped to 0 first. [-]
    operator : str
        One of `OPERATORS`: "aces", "clamp", "exponential", "reinhard".
    exposure : float
        Extra factor applied before the operator. [-]

    Returns
    -------
    ndarray, float64, same shape
        Display-linear values in [0, 1] (NaN stays NaN). [-]
    """
    try:
        curve = OPERATORS[operator]
    except (KeyError, TypeError):
        names = ", ".join(sorted(OPERATORS))
        raise InputError(f"unknown tone-mapping operator {operator!r}; choose one of: {names}",
                         key="operator", value=operator, allowed=names) from None
    x = np.asarray(linear_rgb, dtype=np.float64) * float(exposure)
    return curve(np.clip(x, 0.0, _LARGEST_INPUT))


# Bins of the linear axis for `to_srgb8`, narrower than the closest two steps of its codes
# (1 / (255 x 12.92) = 3.0e-4 apart, in the linear part next to 0)
SRGB8_BINS = 1 << 14


def to_srgb8(display_linear_rgb: ArrayLike) -> np.ndarray:
    """8-bit sRGB codes round(255 · OETF(L)) from display-linear values in [0, 1].

    Parameters
    ----------
    display_linear_rgb : array_like, shape (h, w, 3) (any shape works)
        Output of `tonemap`; values outside [0, 1] are clipped. [-]

    Returns
    -------
    ndarray of uint8, same shape
    """
    lin = np.asarray(display_linear_rgb, dtype=np.float64)
    bad = np.count_nonzero(np.isnan(lin))
    if bad:
        raise InputError(f"cannot encode an image with {bad} NaN values to 8-bit sRGB",
                         key="display_linear_rgb", value=f"{bad} NaN")
    base, step = _srgb8_bins()
    codes = np.empty(lin.shape, dtype=np.uint8)
    _srgb8_codes(lin.reshape(-1), base, step, codes.reshape(-1))
    return codes


@njit(parallel=True, cache=True)
def _srgb8_codes(linear, base, step, out):
    """out[j]: the number of steps at or below linear[j] clipped to [0, 1] (`_srgb8_bins`):
    one bin and at most one comparison per value instead of the transfer function's power."""
    for j in prange(linear.size):
        value = min(max(linear[j], 0.0), 1.0)
        i = min(int(value * SRGB8_BINS), SRGB8_BINS - 1)
        out[j] = base[i] + (1 if value >= step[i] else 0)


@lru_cache(maxsize=1)
def _srgb8_bins() -> tuple[np.ndarray, np.ndarray]:
    """(code at the start of each of SRGB8_BINS bins of [0, 1] (uint8), the step inside the
    bin, or inf where it has none): the steps are the linear values at which round(255
    OETF(L)) goes from k to k + 1, the sRGB decoding of (k + 1/2) / 255, k = 0 .. 254."""
    steps = decode_srgb_transfer((np.arange(255) + 0.5) / 255.0)
    starts = np.arange(SRGB8_BINS) / SRGB8_BINS
    base = np.searchsorted(steps, starts, side="right")
    following = np.append(steps, np.inf)[base]
    step = np.where(following < starts + 1.0 / SRGB8_BINS, following, np.inf)
    base = base.astype(np.uint8)
    base.flags.writeable = step.flags.writeable = False
    return base, step
