"""Write the colorimetric tables skyscatter uses as one .npz, so that rendering does not import
colour-science (about 1-2 s with matplotlib installed).

Source: PyPI colour-science (BSD-3-Clause) datasets, which tabulate the CIE and industry data:
- CIE 1931 2° colour-matching functions, 1 nm, 360-830 nm (CIE 015:2018);
- the chromaticities of the CIE illuminants for that observer (`CCS_ILLUMINANTS`);
- the relative spectral power of CIE illuminants D65, D50 and A (CIE 015:2018, `SDS_ILLUMINANTS`);
- the cone-response matrices of the chromatic adaptation transforms (Bradford: Lam 1985; CAT02:
  Moroney et al. 2002; CAT16: Li et al. 2017; von Kries: Hunt-Pointer-Estevez; XYZ scaling);
- the primaries and whites of the RGB spaces (IEC 61966-2-1 sRGB, ITU-R BT.709, Display P3,
  ITU-R BT.2020, ACEScg AP1, ACES2065-1 AP0).
Values are copied as float64. Run: python scripts/make_data/colour_tables.py (needs
colour-science, a test dependency).
"""

from __future__ import annotations

import sys
from pathlib import Path

import colour
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from reproducible_npz import write_npz  # noqa: E402

TARGET = Path(__file__).resolve().parents[2] / "src/skyscatter/data/colour_cie.npz"
OBSERVER = "CIE 1931 2 Degree Standard Observer"
SPECTRA = ("D65", "D50", "A")
RGB = {"srgb": "sRGB", "rec709": "ITU-R BT.709", "display-p3": "Display P3",
       "rec2020": "ITU-R BT.2020", "acescg": "ACEScg", "aces2065-1": "ACES2065-1"}
ADAPTATION = {"bradford": "Bradford", "cat02": "CAT02", "cat16": "CAT16",
              "von-kries": "Von Kries", "xyz-scaling": "XYZ Scaling"}


def main() -> None:
    cmfs = colour.colorimetry.MSDS_CMFS[OBSERVER]
    illuminants = colour.CCS_ILLUMINANTS[OBSERVER]
    arrays = {
        "cmf_wavelengths_nm": np.asarray(cmfs.wavelengths, dtype=np.float64),
        "cmf_xyz_bar": np.ascontiguousarray(np.asarray(cmfs.values, dtype=np.float64).T),
        "illuminant_names": np.array(list(illuminants)),
        "illuminant_xy": np.array([illuminants[name] for name in illuminants], dtype=float),
        "rgb_names": np.array(list(RGB)),
        "rgb_primaries_xy": np.array([colour.RGB_COLOURSPACES[n].primaries for n in RGB.values()],
                                     dtype=float),
        "rgb_white_xy": np.array([colour.RGB_COLOURSPACES[n].whitepoint for n in RGB.values()],
                                 dtype=float),
        "adaptation_names": np.array(list(ADAPTATION)),
        "adaptation_matrices": np.array([colour.adaptation.CHROMATIC_ADAPTATION_TRANSFORMS[n]
                                         for n in ADAPTATION.values()], dtype=float),
    }
    for name in SPECTRA:
        sd = colour.SDS_ILLUMINANTS[name]
        arrays[f"spd_{name}_wavelengths_nm"] = np.asarray(sd.wavelengths, dtype=np.float64)
        arrays[f"spd_{name}"] = np.asarray(sd.values, dtype=np.float64)
    write_npz(TARGET, arrays)
    print(f"wrote {TARGET} (colour-science {colour.__version__})")


if __name__ == "__main__":
    main()
