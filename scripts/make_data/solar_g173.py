"""Build src/skyscatter/data/solar_astm_g173_etr.npz from pvlib's copy of ASTM G173-03.

Source: the extraterrestrial (ETR) column of the ASTM G173-03 reference spectra ("Derived from
SMARTS v. 2.9.2"), 280–4000 nm, 2002 wavelengths, W m⁻² nm⁻¹, as shipped in PyPI `pvlib`
(pvlib/data/ASTMG173.csv, BSD-3-Clause) and read with
`pvlib.spectrum.get_reference_spectra(standard="ASTM G173-03")`.

The archive is written with fixed zip timestamps, so rebuilding with the same pvlib gives the same
bytes (checksum in data/PROVENANCE.md). Run: `python scripts/make_data/solar_g173.py`.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from reproducible_npz import write_npz

OUT = (Path(__file__).resolve().parents[2] / "src" / "skyscatter" / "data"
       / "solar_astm_g173_etr.npz")


def load_g173_etr() -> tuple[np.ndarray, np.ndarray, str]:
    import pvlib

    table = pvlib.spectrum.get_reference_spectra(standard="ASTM G173-03")
    wavelength_nm = np.asarray(table.index.to_numpy(), dtype=np.float64)
    irradiance = np.asarray(table["extraterrestrial"].to_numpy(), dtype=np.float64)
    return wavelength_nm, irradiance, pvlib.__version__


def main() -> None:
    wavelength_nm, irradiance, pvlib_version = load_g173_etr()
    assert np.all(np.diff(wavelength_nm) > 0), "wavelengths must ascend"
    assert wavelength_nm[0] == 280.0 and wavelength_nm[-1] == 4000.0 and wavelength_nm.size == 2002
    source = (f"ASTM G173-03 extraterrestrial spectrum (SMARTS v2.9.2), pvlib {pvlib_version} "
              "pvlib/data/ASTMG173.csv; wavelength_nm [nm], irradiance [W m-2 nm-1] at 1 AU")
    write_npz(OUT, {"wavelength_nm": wavelength_nm, "irradiance": irradiance,
                    "source": np.array(source)})
    total = float(np.trapezoid(irradiance, wavelength_nm))
    digest = hashlib.sha256(OUT.read_bytes()).hexdigest()
    print(f"wrote {OUT} ({OUT.stat().st_size} B): {wavelength_nm.size} points, "
          f"integral 280-4000 nm = {total:.4f} W m-2, sha256 {digest}")


if __name__ == "__main__":
    main()
