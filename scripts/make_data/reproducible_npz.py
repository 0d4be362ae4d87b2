"""Write .npz files byte for byte reproducibly (fixed zip timestamps), atomically."""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path

import numpy as np

FIXED_TIME = (1980, 1, 1, 0, 0, 0)  # zip timestamps, for byte-reproducible output


def write_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """np.savez layout (one .npy per array) with fixed timestamps; written then renamed."""
    tmp = path.with_suffix(".npz.tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, array in arrays.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, np.require(array, requirements="C"),
                                      allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=FIXED_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buffer.getvalue())
    os.replace(tmp, path)
