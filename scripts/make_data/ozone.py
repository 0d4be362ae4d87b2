"""Build src/skyscatter/data/o3_cross_section_malicet_brion_295k.npz from PyPI musica's TUV-x data.

Source: `musica/configs/tuvx/data/cross_sections/O3_1.nc` of PyPI musica 0.17.2 (Apache-2.0),
an HDF5/netCDF-4 file made by "TUV Data Xformer 1.0" from
`1995Malicet_1998Brion_O3_295.txt`: the O3 absorption cross-section at 295 K,
195-345 nm from Malicet et al. (1995), J. Atmos. Chem. 21, 263, doi:10.1007/BF00696758, and
345.01-830 nm from Brion et al. (1998), J. Atmos. Chem. 30, 291, doi:10.1023/A:1006036924364;
63,501 points every 0.01 nm, cm^2 molecule^-1.

What the script does: it averages the piecewise-linear source over 0.1-nm bins (195.0-195.1, ...,
829.9-830.0 nm; the exact mean of the linear interpolant over each bin), converts cm^2 -> m^2
(x 1e-4) and stores `bin_edges_nm` (6351, float64) and `cross_section_m2` (6350, float32) with
fixed zip timestamps, so rebuilding with the same musica gives the same bytes.
Run: `python scripts/make_data/ozone.py` (needs `pip install musica h5py`).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from reproducible_npz import write_npz

OUT = (Path(__file__).resolve().parents[2] / "src" / "skyscatter" / "data"
       / "o3_cross_section_malicet_brion_295k.npz")
SOURCE_FILE = "configs/tuvx/data/cross_sections/O3_1.nc"
BIN_NM = 0.1


def load_source() -> tuple[np.ndarray, np.ndarray, str, str]:
    """Wavelength [nm], cross-section [cm^2], musica version and the file's header text."""
    import h5py
    import musica

    path = Path(musica.__file__).parent / SOURCE_FILE
    with h5py.File(path, "r") as f:
        wavelength_nm = np.asarray(f["wavelength"][:], dtype=np.float64)
        sigma_cm2 = np.asarray(f["cross_section_parameters"][0], dtype=np.float64)
        header = f["cross_section_parameters"].attrs["hdr"].decode()
        assert f["cross_section_parameters"].attrs["units"].decode() == "cm^2"
        assert float(f["temperature"][0]) == 295.0
    return wavelength_nm, sigma_cm2, musica.__version__, header


def bin_means(wavelength_nm: np.ndarray, values: np.ndarray,
              edges_nm: np.ndarray) -> np.ndarray:
    """Mean of the linear interpolant of (wavelength_nm, values) over each [edge_i, edge_i+1]."""
    cumulative = np.concatenate(([0.0], np.cumsum(0.5 * (values[1:] + values[:-1])
                                                  * np.diff(wavelength_nm))))
    # Integral from wavelength_nm[0] to x of the linear interpolant, exact for any x.
    i = np.clip(np.searchsorted(wavelength_nm, edges_nm, side="right") - 1, 0,
                wavelength_nm.size - 2)
    dx = edges_nm - wavelength_nm[i]
    slope = (values[i + 1] - values[i]) / (wavelength_nm[i + 1] - wavelength_nm[i])
    at_edges = cumulative[i] + values[i] * dx + 0.5 * slope * dx * dx
    return np.diff(at_edges) / np.diff(edges_nm)


def main() -> None:
    wavelength_nm, sigma_cm2, musica_version, header = load_source()
    assert np.all(np.diff(wavelength_nm) > 0), "wavelengths must ascend"
    assert wavelength_nm.size == 63501 and wavelength_nm[0] == 195.0
    assert abs(wavelength_nm[-1] - 830.0) < 1e-9
    assert np.all(sigma_cm2 > 0.0) and "Malicet" in header and "Brion" in header
    n_bins = round((830.0 - 195.0) / BIN_NM)
    edges = 195.0 + BIN_NM * np.arange(n_bins + 1)
    edges[-1] = wavelength_nm[-1]
    sigma_m2 = bin_means(wavelength_nm, sigma_cm2, edges) * 1.0e-4
    source = (f"O3 absorption cross-section, 295 K: Malicet 1995 (195-345 nm) + Brion 1998 "
              f"(345-830 nm); PyPI musica {musica_version} {SOURCE_FILE}; mean over 0.1-nm bins; "
              "bin_edges_nm [nm], cross_section_m2 [m2 molecule-1]")
    write_npz(OUT, {"bin_edges_nm": edges, "cross_section_m2": sigma_m2.astype(np.float32),
                    "source": np.array(source)})
    digest = hashlib.sha256(OUT.read_bytes()).hexdigest()
    at_600 = sigma_m2[np.searchsorted(edges, 600.0) - 1]
    print(f"wrote {OUT} ({OUT.stat().st_size} B): {sigma_m2.size} bins, "
          f"sigma(599.9-600.0 nm) = {at_600:.4e} m2, sha256 {digest}")


if __name__ == "__main__":
    main()
