"""The sun disk composited at the horizon: the planet hides the part below it.

Reference: the circular-segment area of a disk cut by a straight edge (closed form, as
`transport.geometry.disk_fraction_above`), and pixel directions against the horizon plane.
"""

from __future__ import annotations

import math

import numpy as np

from skyscatter.render.camera import PerspectiveCamera
from skyscatter.render.scene import add_sun_disk, sun_direction
from skyscatter.spectrum.star import Star

WAVELENGTHS_NM = np.array([450.0, 550.0, 650.0])


def _disk(elevation_deg: float, camera: PerspectiveCamera, horizon_cos_zenith: float):
    directions, valid = camera.directions()
    spectral = np.zeros(directions.shape[:2] + (WAVELENGTHS_NM.size,))
    add_sun_disk(spectral, camera, directions, valid, sun_direction(90.0 - elevation_deg, 270.0),
                 star=Star.sun(), wavelengths_nm=WAVELENGTHS_NM,
                 transmittance=np.ones(WAVELENGTHS_NM.size),
                 horizon_cos_zenith=horizon_cos_zenith)
    return spectral, directions


def test_pixels_of_the_disk_below_the_horizon_stay_dark():
    # 0.1 deg below the horizontal, 0.27 deg radius: the upper part shows, nothing below it.
    camera = PerspectiveCamera(200, 200, 2.0, heading_deg=270.0)
    spectral, directions = _disk(-0.1, camera, 0.0)
    lit = spectral[..., 1] > 0.0
    assert np.any(lit) and np.all(directions[lit][:, 2] >= 0.0)
    # The lit area is the circular segment above the edge: x = -0.1 / 0.2666 -> 30.7 %;
    # tolerance 2 % of the disk for pixel edges (the disk is ~27 pixels across).
    whole, _ = _disk(5.0, PerspectiveCamera(200, 200, 2.0, heading_deg=270.0, pitch_deg=5.0),
                     -1.0)
    x = -0.1 / math.degrees(Star.sun().angular_radius_rad)
    segment = 0.5 + (x * math.sqrt(1.0 - x * x) + math.asin(x)) / math.pi
    fraction = np.count_nonzero(lit) / np.count_nonzero(whole[..., 1] > 0.0)
    assert abs(fraction - segment) < 0.02


def test_a_sub_pixel_disk_is_dimmed_by_the_part_above_the_horizon():
    # A wide view: the disk goes into one pixel; its flux scales with the visible segment.
    camera = PerspectiveCamera(64, 64, 60.0, heading_deg=270.0)
    omega = camera.pixel_solid_angles()
    above, _ = _disk(1.0, camera, 0.0)
    setting, _ = _disk(0.0, camera, 0.0)  # centre on the horizon: half the disk
    below, _ = _disk(-1.0, camera, 0.0)
    flux = [float(np.sum(image[..., 1] * omega)) for image in (above, setting, below)]
    assert flux[0] > 0.0 and flux[2] == 0.0
    assert abs(flux[1] / flux[0] - 0.5) < 1e-9  # x = 0 in the segment formula, up to rounding
