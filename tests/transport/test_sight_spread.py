"""The peaks' blur of the radiance field for the lines of sight (`transport.sight_spread`)
against a direct quadrature over the sphere: for fields given in closed form (a constant, and
smooth fields with a linear and a quadratic part in the direction, shaped like a sky), the
source K * F - F that the module builds from the field on its (view zenith, azimuth) nodes -
the peak projected on the view's vertical plane, plus the small-angle blur across it - must
match the blur computed by rotating each view through the peak's deflections in 3-D, on every
node of the layout the tables pass (`incoming_radiance`'s in, `multiple_scattering_table`'s
out)."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.transport.sight_spread import (
    SIGHT_THETA,
    _across,
    _blur_zenith,
    _mean_square_angle,
    _vertical_kernel,
    sight_spread_source,
    view_zenith_angles,
)

TRUNCATION_DEG = 15.0
N_ANGLE = 4097
THETA = np.linspace(0.0, np.pi, N_ANGLE)
N_PHI = 13


def peak_phase(width_deg: float) -> np.ndarray:
    """A Gaussian peak clipped at the truncation angle, normalised on the sphere (N_ANGLE, 1)."""
    p = np.where(np.radians(TRUNCATION_DEG) > THETA,
                 np.exp(-0.5 * (THETA / np.radians(width_deg)) ** 2), 0.0)
    return (p / np.trapezoid(p * 2.0 * np.pi * np.sin(THETA), THETA))[:, None]


def directions(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors at zenith angles theta and azimuths phi (broadcast), (..., 3)."""
    return np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi),
                                        np.sin(theta) * np.sin(phi), np.cos(theta)), axis=-1)


def sky_like(v: np.ndarray) -> np.ndarray:
    """A smooth field symmetric about the x-z plane: brighter towards a low 'sun' and the
    horizon (a constant, a linear and two quadratic parts in the direction)."""
    sun = np.array([np.sin(np.radians(80.0)), 0.0, np.cos(np.radians(80.0))])
    return 1.0 + 0.6 * (v @ sun) + 0.9 * (1.0 - v[..., 2] ** 2) + 0.3 * (v @ sun) ** 2


def sphere_blur(field, v: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """K * F at the unit directions v (n, 3): each view turned by the peak's deflections,
    Gauss-Legendre in the deflection angle (0 to the truncation angle) x 64 azimuths."""
    nodes, weights = np.polynomial.legendre.leggauss(48)
    top = np.radians(TRUNCATION_DEG)
    angle = 0.5 * top * (nodes + 1.0)
    weight = 0.5 * top * weights * np.interp(angle, THETA, phase[:, 0]) * np.sin(angle)
    psi = (np.arange(64) + 0.5) * 2.0 * np.pi / 64
    a = np.cross(v, [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(v, a)
    turned = (np.cos(angle)[None, :, None, None] * v[:, None, None, :]
              + np.sin(angle)[None, :, None, None] * (
                  np.cos(psi)[None, None, :, None] * a[:, None, None, :]
                  + np.sin(psi)[None, None, :, None] * b[:, None, None, :]))
    w = weight[:, None] * np.full(psi.size, 2.0 * np.pi / psi.size)[None, :]
    return np.einsum("nij,ij->n", field(turned), w) / w.sum()


@pytest.mark.parametrize("width_deg", [2.0, 4.0])
def test_blur_matches_a_quadrature_over_the_sphere(width_deg: float) -> None:
    phase = peak_phase(width_deg)
    theta = view_zenith_angles()
    phi = np.linspace(0.0, np.pi, N_PHI)
    sky = sky_like(directions(theta[:, None], phi[None, :]))  # (n_theta, n_phi)
    n_r, n_mu_s = 2, 3
    # incoming_radiance's layout: (n_wl, n_theta n_phi, n_r n_mu_s), each node's field scaled
    scale = 1.0 + np.arange(n_r * n_mu_s)
    field = (sky.reshape(1, -1, 1) * scale[None, None, :]).astype(np.float32)
    source = sight_spread_source(field, n_mu_s, N_PHI, (phase, TRUNCATION_DEG))
    assert source.shape == (n_r, SIGHT_THETA, n_mu_s * N_PHI)
    # views away from the zenith and the nadir, where the across-blur holds sin theta
    pick = (theta > np.radians(20.0)) & (theta < np.radians(160.0))
    t, p = np.meshgrid(theta[pick][::8], phi, indexing="ij")
    v = directions(t.ravel(), p.ravel())
    reference = (sphere_blur(sky_like, v, phase) - sky_like(v)).reshape(t.shape)
    # the blur is 3e-3-1e-2 of the field; the small-angle limit across the plane and the
    # projection's 1-degree steps leave 0.7-0.9 % of its largest value (measured; the
    # vertical plane alone would miss 53 %)
    tolerance = 0.03 * np.abs(reference).max()
    nodes = source.reshape(n_r, SIGHT_THETA, n_mu_s, N_PHI)
    for k in range(n_r):
        for m in range(n_mu_s):
            mine = nodes[k, pick, m][::8] / scale[k * n_mu_s + m]
            assert np.abs(mine - reference).max() < tolerance, (k, m)


def test_the_vertical_plane_alone_misses_the_blur_across_it() -> None:
    """The across term is needed: without it the source misses about half of the blur."""
    phase = peak_phase(4.0)
    theta = view_zenith_angles()
    phi = np.linspace(0.0, np.pi, N_PHI)
    values = sky_like(directions(theta[:, None], phi[None, :]))[None, :, :, None]
    vertical = (_blur_zenith(values, _vertical_kernel(phase, TRUNCATION_DEG)) - values)[0, ..., 0]
    pick = np.abs(theta - np.radians(85.0)).argmin()
    v = directions(theta[pick], phi)
    reference = sphere_blur(sky_like, v, phase) - sky_like(v)
    assert np.abs(vertical[pick] - reference).max() > 0.2 * np.abs(reference).max()


def test_a_uniform_field_has_no_source() -> None:
    phase = peak_phase(3.0)
    theta = np.linspace(0.0, np.pi, SIGHT_THETA)
    values = np.full((2, SIGHT_THETA, N_PHI, 1), 7.0)
    change = (_blur_zenith(values, _vertical_kernel(phase, TRUNCATION_DEG)) - values
              + _across(values, theta, _mean_square_angle(phase)))
    assert np.abs(change).max() < 1e-12 * 7.0
