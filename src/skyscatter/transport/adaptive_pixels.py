"""Adaptive refinement over an image's pixels: an expensive per-ray quantity is computed on a
coarse lattice first, then, level by level, each pixel between computed ones takes its
neighbours' mean where they agree and is computed itself where they do not.

A pixel grid (h, w) holds the index of each pixel's ray (-1 where the camera has none). At
spacing s the rays at rows and columns that are multiples of s are evaluated; halving s, the
new pixels lie between two known ones (same row or column) or in the middle of four; one
whose neighbours are missing (the image's edge, a fisheye's rim) is evaluated. Where the
evaluation is noisy with a few likely outcomes (a jittered march that meets a thin cloud or
misses it), agreement among few neighbours is partly luck and settling on it biases the image
towards the likelier outcome: the evaluation should be made nearly deterministic first. Features
narrower than the coarse spacing can fall between its points unseen, so the spacing is
chosen from the angle between neighbouring rays (`coarse_spacing`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["MAX_SPACING", "SPACING_ANGLE_RAD", "coarse_spacing", "refine"]

MAX_SPACING = 8  # pixels between the first lattice's points, at most
SPACING_ANGLE_RAD = np.radians(0.75)  # ... and at most this angle apart
SETTLE_CHUNK = 1 << 16  # pixels settled at once: bounds the neighbour gathers


def coarse_spacing(rays: np.ndarray, pixels: np.ndarray) -> int:
    """The first lattice's spacing: the largest power of two up to `MAX_SPACING` that keeps
    its points within `SPACING_ANGLE_RAD` of each other, from the median angle between
    horizontally neighbouring unit `rays` (n, 3) of `pixels` (h, w)."""
    left, right = pixels[::8, :-1].ravel(), pixels[::8, 1:].ravel()
    both = (left >= 0) & (right >= 0)
    if not both.any():
        return 1
    cosines = np.einsum("ij,ij->i", rays[left[both]], rays[right[both]])
    step = float(np.median(np.arccos(np.clip(cosines, -1.0, 1.0))))
    spacing = 1
    while spacing < MAX_SPACING and 2 * spacing * step <= SPACING_ANGLE_RAD:
        spacing *= 2
    return spacing


def refine(pixels: np.ndarray, spacing: int, evaluate: Callable[[np.ndarray], None],
           settle: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> int:
    """Fill every ray of `pixels` (h, w) (module docstring) starting from a lattice of
    `spacing` (a power of two): `evaluate(indices (m,))` computes those rays;
    `settle(targets (m,), neighbours (m, k))` fills the targets whose neighbours agree and
    returns which (bool (m,)). Returns the number of rays evaluated."""
    height, width = pixels.shape
    coarse = pixels[::spacing, ::spacing]
    first = coarse[coarse >= 0]
    evaluate(first)
    evaluated = first.size
    half = spacing // 2
    while half >= 1:
        for dy, dx in ((0, half), (half, 0), (half, half)):
            evaluated += _fill_level(pixels, (spacing, dy, dx), evaluate, settle)
        spacing, half = half, half // 2
    return evaluated


def _fill_level(pixels: np.ndarray, lattice: tuple[int, int, int],
                evaluate: Callable[[np.ndarray], None],
                settle: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> int:
    """The pixels at offset (dy, dx) from the known lattice of `spacing`: settled from their
    two or four known neighbours where they agree, else evaluated; returns how many were
    evaluated."""
    height, width = pixels.shape
    spacing, dy, dx = lattice
    rows, cols = np.arange(dy, height, spacing), np.arange(dx, width, spacing)
    row, col = np.meshgrid(rows, cols, indexing="ij")
    targets = pixels[row, col].ravel()
    offsets = [(-dy, 0), (dy, 0)] if dx == 0 else [(0, -dx), (0, dx)] if dy == 0 else [
        (-dy, -dx), (-dy, dx), (dy, -dx), (dy, dx)]
    neighbours = np.full((targets.size, len(offsets)), -1)
    for k, (oy, ox) in enumerate(offsets):
        y, x = (row + oy).ravel(), (col + ox).ravel()
        inside = (y < height) & (x < width)
        neighbours[inside, k] = pixels[y[inside], x[inside]]
    keep = targets >= 0
    targets, neighbours = targets[keep], neighbours[keep]
    complete = (neighbours >= 0).all(axis=1)
    unsettled = [targets[~complete]]
    targets, neighbours = targets[complete], neighbours[complete]
    for start in range(0, targets.size, SETTLE_CHUNK):
        some = targets[start:start + SETTLE_CHUNK]
        unsettled.append(some[~settle(some, neighbours[start:start + SETTLE_CHUNK])])
    rest = np.concatenate(unsettled)
    evaluate(rest)
    return rest.size
