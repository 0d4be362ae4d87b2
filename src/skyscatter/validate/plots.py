"""Figures of the validation report: matplotlib without a display, saved atomically.

Public names: `new_figure`, `save_figure`.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never a window

import matplotlib.pyplot as plt  # noqa: E402 (after choosing the backend)

from skyscatter.render.image_io import atomic_write  # noqa: E402

__all__ = ["new_figure", "save_figure"]

DPI = 110


def new_figure(n_rows: int = 1, n_cols: int = 1, width_in: float = 6.4,
               height_in: float = 4.2, **kwargs):
    """(figure, axes) of `n_rows` x `n_cols` panels, each `width_in` x `height_in` inches;
    `axes` is a 2-D array when there is more than one panel."""
    figure, axes = plt.subplots(n_rows, n_cols, figsize=(width_in * n_cols, height_in * n_rows),
                                squeeze=n_rows * n_cols == 1, **kwargs)
    return figure, axes


def save_figure(figure, output_dir: Path, name: str) -> str:
    """Save `figure` as `output_dir/name` (PNG) through a temporary file and close it; return
    `name` (the path relative to the report)."""
    figure.tight_layout()
    try:
        atomic_write(Path(output_dir) / name,
                     lambda temporary: figure.savefig(temporary, dpi=DPI, format="png"))
    finally:
        plt.close(figure)
    return name
