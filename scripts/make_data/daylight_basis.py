"""Write the CIE daylight basis functions S0, S1, S2 (CIE 015:2018, Table 6; 300-830 nm every
5 nm) as src/skyscatter/data/cie_daylight_basis.npz, for spectra of daylight from a
chromaticity (`spectrum.daylight`).

Source: PyPI colour-science (BSD-3-Clause), `SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES`, which
tabulates the CIE table. Values are copied as float64. Run:
python scripts/make_data/daylight_basis.py (needs colour-science, a test dependency).
"""

from __future__ import annotations

import sys
from pathlib import Path

import colour
import numpy as np
from colour.colorimetry.datasets.illuminants.sds_d_illuminant_series import (
    SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES,
)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from reproducible_npz import write_npz  # noqa: E402

TARGET = Path(__file__).resolve().parents[2] / "src/skyscatter/data/cie_daylight_basis.npz"


def main() -> None:
    basis = SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES
    wavelengths = np.asarray(basis["S0"].wavelengths, dtype=np.float64)
    for name in ("S1", "S2"):
        assert np.array_equal(basis[name].wavelengths, wavelengths)
    write_npz(TARGET, {
        "wavelengths_nm": wavelengths,
        "basis": np.stack([np.asarray(basis[n].values, dtype=np.float64)
                           for n in ("S0", "S1", "S2")]),
    })
    print(f"wrote {TARGET} (colour-science {colour.__version__})")


if __name__ == "__main__":
    main()
