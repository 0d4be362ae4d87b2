"""The forward model of a fit from a solver: the measured quantities of one atmosphere.

`SolverModel(document, path, "hillaire").predict({key: value}, measurements)` builds the
atmosphere of the config with those values (`atmosphere.config_overrides.atmosphere_with`)
and computes, for each measured value,

- radiance: the solver's diffuse sky radiance at the row's geometry, monochromatic at its
  wavelength (as `api.sky_radiance_rows`: observer on the ground or at `altitude_m`, the sun
  at azimuth 0, the view at the row's azimuth relative to it);
- transmittance: exp(-optical depth along the path to the sun), ray marched through the
  spherical shell (`transport.transmittance.ray_marched_transmittance`), the same for every
  solver (the Beer-Lambert law needs none);
- chromaticity and luminance: CIE 1931 x, y and Y [cd m^-2] of the solver's sky radiance on
  `COLOUR_BANDS` bands over 360-830 nm (`spectrum.colour.spectral_to_xyz`,
  `xy_chromaticity`), the grid `skyscatter render` uses by default, so a rendered image's
  luminance is this model's.

The Monte Carlo solver also returns the standard error of each radiance (and, to first order,
of x and y), which a fit adds to the model error. The last prediction is kept, so the fit's
repeated calls at one point cost nothing.

Public names: `COLOUR_BANDS`, `FAST_SOLVERS`, `SolverModel`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.atmosphere.config_overrides import atmosphere_with
from skyscatter.fit.measurements import Measurements
from skyscatter.fit.model_error import model_error
from skyscatter.render.radiance_grid import sky_radiance_and_error
from skyscatter.render.scene import sun_direction
from skyscatter.spectrum.colour import spectral_to_xyz, xy_chromaticity
from skyscatter.spectrum.grid import checked_data_wavelengths, wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import SolverOptions, make_solver
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["COLOUR_BANDS", "FAST_SOLVERS", "SolverModel"]

FAST_SOLVERS = ("hillaire", "schuler", "single")  # seconds or less per atmosphere
COLOUR_BANDS = 16  # the bands of images (api.DEFAULT_WAVELENGTH_BINS): x, y within 0.001
TRANSMITTANCE_INTERVALS = 1024  # as validate.mars_mer_transmittance: quadrature error ~1e-4


def folded_azimuth_deg(azimuth_deg: np.ndarray) -> np.ndarray:
    """Relative azimuth folded into [0, 180] deg: the sky is symmetric about the sun's
    vertical plane (a spherical planet with the sun at one azimuth)."""
    return np.abs((np.asarray(azimuth_deg, dtype=np.float64) + 180.0) % 360.0 - 180.0)


class SolverModel:
    """The forward model of `solver` (a registered name) for the config `document` read from
    `path`: `samples` ray-marching samples per view ray (paths for the Monte Carlo), the
    config's scattering orders, tables kept in memory (not cached: each atmosphere of a fit
    is used once)."""

    def __init__(self, document: Mapping[str, Any], path: Path, solver: str, *,
                 samples: int = 64, altitude_m: float = 0.0,
                 model_error_override: float | None = None) -> None:
        self.document, self.path, self.name = document, Path(path), solver
        self.samples, self.altitude_m = int(samples), float(altitude_m)
        self.model_error_override = model_error_override
        self._last: tuple[tuple, tuple[np.ndarray, np.ndarray]] | None = None

    def check(self, measurements: Measurements) -> None:
        """InputError, before any work, for wavelengths outside the shipped data."""
        wavelengths = measurements.wavelength_nm[~np.isnan(measurements.wavelength_nm)]
        if wavelengths.size:
            checked_data_wavelengths(np.unique(wavelengths), True, name="wavelength_nm")

    def predict(self, values: Mapping[str, float], measurements: Measurements
                ) -> tuple[np.ndarray, np.ndarray]:
        """(predicted value, its model error sigma_model) of each measured value."""
        point = tuple(sorted((k, float(v)) for k, v in values.items()))
        if self._last is not None and self._last[0] == point:
            return self._last[1]
        atmosphere = atmosphere_with(self.document, self.path, dict(point))
        options = SolverOptions(n_samples=self.samples, orders=atmosphere.scattering_orders)
        predicted = np.full(measurements.size, np.nan)
        noise = np.zeros(measurements.size)
        index = measurements.where("radiance")
        if index.size:
            wavelengths = np.unique(measurements.wavelength_nm[index])
            engine = make_solver(self.name, atmosphere.optical_profile(wavelengths,
                                                                       monochromatic=True),
                                 options)
            radiance, error = self._sky(engine, measurements, index)
            column = np.searchsorted(wavelengths, measurements.wavelength_nm[index])
            rows = np.arange(index.size)
            predicted[index] = radiance[rows, column]
            noise[index] = error[rows, column]
        index = measurements.where("transmittance")
        if index.size:
            wavelengths = np.unique(measurements.wavelength_nm[index])
            profile = atmosphere.optical_profile(wavelengths, monochromatic=True)
            position = observer_position(self.altitude_m, profile.bottom_radius_m)
            suns = np.array([sun_direction(z, 0.0) for z in measurements.sun_zenith_deg[index]])
            transmittance = ray_marched_transmittance(profile, position, suns,
                                                      n_samples=TRANSMITTANCE_INTERVALS)
            predicted[index] = transmittance[np.arange(index.size), np.searchsorted(
                wavelengths, measurements.wavelength_nm[index])]
        chroma = measurements.where("chromaticity_x")
        luminance = measurements.where("luminance")
        if chroma.size or luminance.size:
            grid = wavelength_grid(COLOUR_BANDS)
            engine = make_solver(self.name, atmosphere.optical_profile(grid), options)
            index = np.concatenate([chroma, luminance])
            radiance, error = self._sky(engine, measurements, index)
            xyz = spectral_to_xyz(radiance, grid)
            # first-order noise of x, y and Y from the radiance's: perturb by one standard error
            shifted = spectral_to_xyz(radiance + error, grid)
            xy, xy_shifted = xy_chromaticity(xyz), xy_chromaticity(shifted)
            n = chroma.size
            for offset in (0, 1):  # y follows x in `measurements`
                predicted[chroma + offset] = xy[:n, offset]
                noise[chroma + offset] = np.abs(xy_shifted[:n, offset] - xy[:n, offset])
            predicted[luminance] = xyz[n:, 1]
            noise[luminance] = np.abs(shifted[n:, 1] - xyz[n:, 1])
        sigma = np.hypot(model_error(self.name, measurements.kind, predicted,
                                     self.model_error_override), noise)
        self._last = (point, (predicted, sigma))
        return predicted, sigma

    def _sky(self, engine, measurements: Measurements, index: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """Radiance and its standard error (zero but for the Monte Carlo), (len(index), n_wl),
        at the geometries of the values `index`."""
        profile = engine.profile
        position = observer_position(self.altitude_m, profile.bottom_radius_m)
        radiance = np.zeros((index.size, profile.n_wavelengths))
        error = np.zeros_like(radiance)
        suns = measurements.sun_zenith_deg[index]
        for sun_zenith in np.unique(suns):
            at = np.flatnonzero(suns == sun_zenith)
            views = local_frame_directions(
                np.radians(measurements.view_zenith_deg[index[at]]),
                np.radians(folded_azimuth_deg(measurements.relative_azimuth_deg[index[at]])))
            radiance[at], noise = sky_radiance_and_error(engine, position, views,
                                                         sun_direction(float(sun_zenith), 0.0))
            if noise is not None:
                error[at] = noise
        return radiance, error
