"""Airglow against published night-sky brightness, the thin-shell geometry and its own totals."""

import math

import numpy as np
import pytest

from skyscatter.render.airglow import (
    AIRGLOW_LINES,
    CONTINUUM_R_PER_NM,
    airglow_radiance,
    van_rhijn_factor,
)
from skyscatter.spectrum.grid import cell_edges, wavelength_grid
from skyscatter.spectrum.magnitudes import V_ZERO_POINT_FLUX, v_band_mean
from skyscatter.spectrum.star import PLANCK, SPEED_OF_LIGHT

R = 6_371_000.0
ARCSEC2_SR = (math.pi / 180.0 / 3600.0) ** 2


def test_zenith_airglow_is_as_bright_as_the_dark_night_sky_allows():
    # The darkest natural skies measure 21.9-22.0 V mag arcsec^-2 at the zenith (Benn &
    # Ellison 1998, La Palma; Falchi et al. 2016), airglow being the largest part; airglow
    # alone varies by about a factor of two (0.75 mag) with season and solar cycle. So: not
    # brighter than 21.6, not fainter than 23.0.
    wavelengths = wavelength_grid(64)
    radiance = airglow_radiance(np.array([1.0]), wavelengths, R, R)[0]
    flux_per_arcsec2 = v_band_mean(wavelengths, radiance * ARCSEC2_SR)
    magnitude = -2.5 * math.log10(float(flux_per_arcsec2) / V_ZERO_POINT_FLUX)
    assert 21.6 < magnitude < 23.0


def test_van_rhijn_factor_is_the_slant_path_through_a_thin_shell():
    # Independent geometry: the length of a ray from the ground through a shell between
    # R + h and R + h + dh, over dh, by ray-sphere intersections.
    h, dh = 97e3, 10.0
    for zenith_deg in (0.0, 45.0, 80.0, 90.0):
        mu = math.cos(math.radians(zenith_deg))

        def distance_to(radius, mu=mu):
            return -R * mu + math.sqrt((R * mu) ** 2 - R * R + radius * radius)

        path = distance_to(R + h + dh) - distance_to(R + h)
        assert van_rhijn_factor(mu, R, R + h) == pytest.approx(path / dh, rel=1e-3)


def test_band_integrated_photons_add_up_to_the_tabulated_rayleighs():
    # Summing radiance x cell width / photon energy over a grid gives the photon radiance of
    # all lines inside it plus the continuum over the grid's span: 1 R = 1e10 / (4 pi)
    # photons s^-1 m^-2 sr^-1, for any grid.
    for n in (16, 200):
        wavelengths = wavelength_grid(n)
        edges = cell_edges(wavelengths)
        radiance = airglow_radiance(np.array([1.0]), wavelengths, R, R)[0]
        photons = radiance * np.diff(edges) / (PLANCK * SPEED_OF_LIGHT / (wavelengths * 1e-9))
        span = min(edges[-1], 830.0) - max(edges[0], 400.0)
        rayleighs = (sum(i for wl, _, i in AIRGLOW_LINES if edges[0] <= wl < edges[-1])
                     + CONTINUUM_R_PER_NM * span)
        # the continuum's photon energy is taken at the cell centres: 1 % over a 30 nm cell
        assert photons.sum() == pytest.approx(rayleighs * 1e10 / (4 * math.pi), rel=0.01)
    below = airglow_radiance(np.array([-0.2]), wavelength_grid(16), R, R)
    assert np.all(below == 0.0)
