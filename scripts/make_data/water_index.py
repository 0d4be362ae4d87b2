"""Write the complex refractive index of liquid water, 300-1000 nm, as CSV.

Source: Segelstein (1981), "The complex refractive index of water", M.S. thesis, University of
Missouri-Kansas City, as shipped in PyPI miepython 3.3.0 (MIT): miepython/data/
segelstein81_index.txt (columns: wavelength [µm], real index n, imaginary index k >= 0).
The rows from the last one at or below 300 nm to the first one at or above 1000 nm are kept;
n and k are copied as printed, the wavelength is converted to nm.
Run: python scripts/make_data/water_index.py  (needs `pip install miepython==3.3.0`).
"""

from __future__ import annotations

import os
from importlib.metadata import version
from pathlib import Path

import miepython

SOURCE = Path(miepython.__file__).parent / "data" / "segelstein81_index.txt"
TARGET = Path(__file__).resolve().parents[2] / "src/skyscatter/data/refractive_index_water.csv"
LOW_NM, HIGH_NM = 300.0, 1000.0


def main() -> None:
    rows = []
    for line in SOURCE.read_text().splitlines():
        fields = line.split()
        try:
            wavelength_nm = float(fields[0]) * 1000.0
        except (IndexError, ValueError):
            continue  # the citation and the column header
        rows.append((wavelength_nm, fields[1], fields[2]))
    first = max(i for i, row in enumerate(rows) if row[0] <= LOW_NM)
    last = min(i for i, row in enumerate(rows) if row[0] >= HIGH_NM)
    header = ("# Liquid water, complex refractive index m = n + i k: Segelstein (1981), "
              "M.S. thesis, University of Missouri-Kansas City.\n"
              f"# From PyPI miepython {version('miepython')} (MIT) miepython/data/"
              "segelstein81_index.txt (wavelength in µm there); "
              "made by scripts/make_data/water_index.py\n"
              "wavelength_nm,n,k\n")
    body = "".join(f"{wl:.6g},{n},{k}\n" for wl, n, k in rows[first:last + 1])
    temporary = TARGET.with_suffix(".csv.tmp")
    temporary.write_text(header + body)
    os.replace(temporary, TARGET)


if __name__ == "__main__":
    main()
