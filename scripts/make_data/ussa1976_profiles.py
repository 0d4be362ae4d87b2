"""Write the US Standard Atmosphere 1976 air and ozone number-density profiles as CSV.

Source: PyPI musica 0.17.2 (Apache-2.0), configs/tuvx/data/profiles/atmosphere/ussa.dens and
ussa.ozone (U.S. Standard Atmosphere 1976, 45 N annual means; ozone 0-1 km filled with 40 ppb).
Run: python scripts/make_data/ussa1976_profiles.py  (needs `pip install musica`).
"""

from __future__ import annotations

import os
from pathlib import Path

import musica
import numpy as np

SOURCE = Path(musica.__file__).parent / "configs/tuvx/data/profiles/atmosphere"
TARGET = Path(__file__).resolve().parents[2] / "src/skyscatter/atmosphere/presets"
CM3_TO_M3 = 1e6  # molecules cm^-3 -> molecules m^-3


def convert(source_name: str, target_name: str, what: str) -> None:
    table = np.loadtxt(SOURCE / source_name, comments="#")
    altitude_m = table[:, 0] * 1000.0
    density_m3 = table[:, 1] * CM3_TO_M3
    header = (f"# {what}: U.S. Standard Atmosphere 1976, 45 N annual mean.\n"
              f"# From PyPI musica 0.17.2 (Apache-2.0) configs/tuvx/data/profiles/atmosphere/"
              f"{source_name}; made by scripts/make_data/ussa1976_profiles.py\n"
              "altitude_m,number_density_m3\n")
    rows = "".join(f"{z:.1f},{n:.4e}\n" for z, n in zip(altitude_m, density_m3, strict=True))
    temporary = TARGET / (target_name + ".tmp")
    temporary.write_text(header + rows)
    os.replace(temporary, TARGET / target_name)


if __name__ == "__main__":
    convert("ussa.dens", "ussa1976_air.csv", "air number density [m^-3]")
    convert("ussa.ozone", "ussa1976_ozone.csv", "ozone number density [m^-3]")
