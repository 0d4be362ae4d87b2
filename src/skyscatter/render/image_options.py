"""How a sky image becomes files (`ImageOptions`): exposure, tone curve, colour space, white
balance and what an EXR holds, checked when made.

The names are checked by membership in the tables that define them: the tone curves of
`render.tonemap.OPERATORS`, the colour spaces of `spectrum.colour.RGB_SPACES` (any case, as
`xyz_to_rgb` reads them) and the EXR contents of `EXR_UNITS`; exposures within `checks.EV`.
"""

from __future__ import annotations

from dataclasses import dataclass

from skyscatter.checks import EV, checked_choice
from skyscatter.render.tonemap import OPERATORS
from skyscatter.spectrum.colour import RGB_SPACES

__all__ = ["EXR_CONTENTS", "EXR_UNITS", "ImageOptions"]

# What an EXR can hold -> the unit written in its header
EXR_UNITS = {"rgb": "linear RGB, Y = 1 for 1 cd/m^2", "luminance": "cd/m^2",
             "spectral": "W m^-2 sr^-1 nm^-1",
             "spectral-fichet2021": "S0 channels: W m^-2 sr^-1 nm^-1; R, G, B: linear RGB, "
                                    "Y = 1 for 1 cd/m^2"}
EXR_CONTENTS = tuple(EXR_UNITS)


@dataclass(frozen=True, kw_only=True)
class ImageOptions:
    """The choices of `api.save_image`.

    ev100: the exposure value [EV at ISO 100], or None to meter it (`render.exposure`);
    compensation_ev: stops added to the exposure [EV]; operator: the tone curve
    (`render.tonemap.OPERATORS`); colour_space: the RGB space of the PNG and the "rgb" EXR
    (`spectrum.colour.RGB_SPACES`); balance_to_light: adapt the star's white to D65;
    exr_content: "rgb", "luminance", "spectral" or "spectral-fichet2021" (`EXR_UNITS`;
    `render.spectral_exr`); adapt_to_night: meter night
    skies as night. InputError when made with an exposure outside [-40, 40] or an unknown
    name."""

    ev100: float | None = None
    compensation_ev: float = 1.0
    operator: str = "aces"
    colour_space: str = "srgb"
    balance_to_light: bool = False
    exr_content: str = "rgb"
    adapt_to_night: bool = False

    def __post_init__(self) -> None:
        if self.ev100 is not None:
            EV.check("ev100", self.ev100)
        EV.check("compensation_ev", self.compensation_ev)
        checked_choice("EXR content", "exr_content", self.exr_content, EXR_CONTENTS)
        checked_choice("tone-mapping operator", "operator", self.operator, sorted(OPERATORS))
        checked_choice("colour space", "colour_space", self.colour_space, RGB_SPACES,
                       fold_case=True)
