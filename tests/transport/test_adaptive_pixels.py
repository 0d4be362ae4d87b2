"""Adaptive refinement over pixels (transport/adaptive_pixels.py) against closed forms: a
linear image is exact from the coarse lattice alone, a straight edge is found exactly, and the
lattice spacing follows the angle between neighbouring rays."""

import numpy as np
import pytest

from skyscatter.transport.adaptive_pixels import MAX_SPACING, coarse_spacing, refine


class Recorder:
    """Evaluates `truth` at the rays asked for; settles a pixel to its neighbours' mean where
    they spread by at most `tolerance`."""

    def __init__(self, truth: np.ndarray, tolerance: float) -> None:
        self.truth, self.tolerance = truth, tolerance
        self.values = np.full(truth.size, np.nan)
        self.asked = []

    def evaluate(self, indices: np.ndarray) -> None:
        self.asked.append(indices)
        self.values[indices] = self.truth[indices]

    def settle(self, targets: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
        around = self.values[neighbours]
        assert not np.isnan(around).any()  # neighbours are known before they are used
        agree = np.ptp(around, axis=1) <= self.tolerance
        self.values[targets[agree]] = around[agree].mean(axis=1)
        return agree


def _pixels(height: int, width: int, valid: np.ndarray | None = None) -> np.ndarray:
    valid = np.ones((height, width), bool) if valid is None else valid
    pixels = np.full((height, width), -1)
    pixels[valid] = np.arange(int(valid.sum()))
    return pixels


@pytest.mark.parametrize("spacing", [2, 4, 8])
def test_a_linear_image_is_exact_from_the_lattice(spacing):
    # The mean of two or four neighbours of a linear function is its value in the middle:
    # nothing but the lattice and the pixels at the image's far edges needs evaluating.
    height, width = 61, 83
    y, x = np.mgrid[:height, :width]
    truth = (0.3 * y + 0.7 * x + 2.0).ravel()
    recorder = Recorder(truth, tolerance=np.inf)
    evaluated = refine(_pixels(height, width), spacing, recorder.evaluate, recorder.settle)
    np.testing.assert_allclose(recorder.values, truth, rtol=1e-12)
    asked = np.concatenate(recorder.asked)
    assert evaluated == asked.size == np.unique(asked).size  # each ray at most once
    lattice = ((height - 1) // spacing + 1) * ((width - 1) // spacing + 1)
    assert evaluated <= lattice + spacing * (height + width)


def test_a_straight_edge_is_found_exactly():
    # A half-plane is convex and so is its complement: a pixel between two or four
    # neighbours on one side is on that side, so with no tolerance the edge comes out exact.
    height, width = 64, 64
    y, x = np.mgrid[:height, :width]
    truth = (0.37 * x + y > 30.5).astype(float).ravel()
    recorder = Recorder(truth, tolerance=0.0)
    evaluated = refine(_pixels(height, width), 8, recorder.evaluate, recorder.settle)
    np.testing.assert_array_equal(recorder.values, truth)
    assert evaluated < truth.size / 2  # refined along the edge only


def test_pixels_without_rays_are_skipped_and_every_ray_is_filled():
    # A fisheye's disk: the rim's pixels lack neighbours and are evaluated themselves.
    size = 50
    y, x = np.mgrid[:size, :size] - (size - 1) / 2
    valid = np.hypot(x, y) <= size / 2
    truth = np.random.default_rng(5).random(int(valid.sum()))
    recorder = Recorder(truth, tolerance=0.0)
    refine(_pixels(size, size, valid), 4, recorder.evaluate, recorder.settle)
    asked = np.concatenate(recorder.asked)
    assert asked.min() >= 0
    np.testing.assert_array_equal(recorder.values, truth)  # random: every ray evaluated


@pytest.mark.parametrize(("step_deg", "expected"), [(0.02, MAX_SPACING), (0.1, 4), (0.3, 2),
                                                    (0.5, 1)])
def test_the_lattice_spacing_keeps_its_points_within_the_angle(step_deg, expected):
    # Rays along a fan of known angular step: the spacing is the largest power of two s
    # (up to MAX_SPACING) with s step <= 0.75 deg.
    height, width = 16, 40
    azimuth = np.radians(step_deg) * np.arange(width)
    rays = np.stack([np.cos(azimuth), np.sin(azimuth), np.zeros(width)], axis=-1)
    rays = np.tile(rays, (height, 1))
    assert coarse_spacing(rays, _pixels(height, width)) == expected
