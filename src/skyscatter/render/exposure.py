"""The exposure policy of a sky image: which meter sets the EV100, and the 8-bit display image.

The meters and the curves themselves are in `render.tonemap`; this module says which one a
picture gets:

* a view from space (`SkyImage.from_space`): the incident-light meter under the star's
  top-of-atmosphere light (`incident_ev100`), so sunlit white is white against black space;
* a night-adapted picture: the reflected-light meter with the night key
  (`night_adapted_exposure`), darker than a daylight grey;
* otherwise the reflected-light meter over the sky pixels (`auto_ev100`, geometric mean);
* a time-lapse frame: the night-adapted meter through a first-order low-pass in simulated time
  (`adapted_ev100`), so day, twilight and night flow into each other.
"""

from __future__ import annotations

import numpy as np

from skyscatter.render.scene import SkyImage
from skyscatter.render.tonemap import (
    adapted_ev100,
    auto_ev100,
    exposure_scale,
    incident_ev100,
    night_adapted_exposure,
    to_srgb8,
    tonemap,
)
from skyscatter.spectrum.colour import spectral_to_xyz

__all__ = ["display_rgb8", "frame_ev100", "metered_ev100"]


def _night_adapted_ev100(image: SkyImage, xyz: np.ndarray) -> float:
    """The reflected-light meter over the sky pixels of `xyz` with the night key, the night
    shift included. [EV]"""
    metered, night = night_adapted_exposure(xyz[..., 1], image.sky)
    return metered - night


def metered_ev100(image: SkyImage, xyz: np.ndarray, adapt_to_night: bool = False) -> float:
    """The EV100 of `image` when none is given: incident-light metering of the starlight for
    views from space, else the reflected-light meter over the sky pixels of `xyz` (the
    image's XYZ, shape (h, w, 3)), night-adapted (the returned exposure includes the night
    shift) with `adapt_to_night`. [EV]"""
    if image.from_space:
        return incident_ev100(float(spectral_to_xyz(image.light_spectrum,
                                                    image.wavelengths_nm)[1]))
    if adapt_to_night:
        return _night_adapted_ev100(image, xyz)
    return auto_ev100(xyz[..., 1], image.sky)


def frame_ev100(previous_ev100: float | None, image: SkyImage, xyz: np.ndarray,
                elapsed_s: float, adaptation_time_s: float) -> float:
    """The EV100 of a time-lapse frame: the night-adapted meter of `image` (XYZ `xyz`)
    followed from `previous_ev100` (None for the first frame) through a low-pass of time
    constant `adaptation_time_s` over `elapsed_s` of simulated time (`adapted_ev100`). [EV]"""
    return adapted_ev100(previous_ev100, _night_adapted_ev100(image, xyz), abs(elapsed_s),
                         adaptation_time_s)


def display_rgb8(linear_rgb: np.ndarray, valid: np.ndarray, ev100: float,
                 compensation_ev: float, operator: str) -> np.ndarray:
    """The 8-bit display image (h, w, 3) of `linear_rgb` [cd m^-2 scale] exposed at `ev100` +
    `compensation_ev`, tone-mapped with `operator`, black outside the `valid` pixels."""
    display = tonemap(linear_rgb, operator, exposure_scale(ev100, compensation_ev))
    return to_srgb8(display * valid[..., None])
