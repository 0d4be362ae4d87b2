"""The sphere integral of the orders >= 2 against the matrices written out from the phase
functions' closed forms, with and without the rank-5 path of quadratic phase functions."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.optics.phase import henyey_greenstein, rayleigh
from skyscatter.transport.phase_quadrature import (
    phase_quadrature,
    source_function,
    sphere_grids,
)
from skyscatter.transport.tables import TableResolution, coarse_resolution

# A small grid keeps the dense reference cheap; the factorisation does not depend on its size.
RESOLUTION = TableResolution(scattering_r=4, scattering_mu_s=6, sphere_theta=16, sphere_phi=8,
                             density_theta=9, density_phi=5)
N_ANGLE = 4097


def closed_form_matrix(phase, resolution: TableResolution) -> np.ndarray:
    """P[o, i] = (p(v_o . w_i) + p(v_o . w_i')) dOmega_i, rows normalised to 1, from the closed
    form `phase` (a function of the cosine)."""
    _, _, solid, out, incoming, mirrored = sphere_grids(resolution)
    matrix = (phase(out @ incoming.T) + phase(out @ mirrored.T)) * solid[None, :]
    return matrix / matrix.sum(axis=1, keepdims=True)


def sampled(phase) -> np.ndarray:
    """`phase` sampled at N_ANGLE angles uniform over [0, pi], (n_angle,)."""
    return phase(np.cos(np.linspace(0.0, np.pi, N_ANGLE)))


def depolarised_rayleigh(c: np.ndarray) -> np.ndarray:
    """Rayleigh with depolarisation factor 0.0279 (Young 1980, Appl. Opt. 19, 3427):
    p = 3/(16 pi) (1 + 3 gamma + (1 - gamma) c^2) / (1 + 2 gamma), gamma = rho / (2 - rho)."""
    gamma = 0.0279 / (2.0 - 0.0279)
    return 3.0 / (16.0 * np.pi) * (1.0 + 3.0 * gamma + (1.0 - gamma) * c * c) / (1.0 + 2.0 * gamma)


def hg(c: np.ndarray) -> np.ndarray:
    return henyey_greenstein(c, 0.6)


def isotropic(c: np.ndarray) -> np.ndarray:
    return np.full_like(c, 1.0 / (4.0 * np.pi))


def test_quadratic_phase_functions_take_the_rank_5_path_and_others_the_full_matrix():
    phase = np.stack([np.stack([sampled(f)] * 2, axis=-1)
                      for f in (rayleigh, hg, depolarised_rayleigh, isotropic)])
    quadrature = phase_quadrature(phase, RESOLUTION)
    assert list(quadrature.quadratic) == [0, 2, 3]
    assert list(quadrature.full) == [1]


@pytest.mark.parametrize("phase", [rayleigh, depolarised_rayleigh, isotropic])
def test_the_rank_5_matrix_is_the_closed_form_matrix(phase):
    quadrature = phase_quadrature(sampled(phase)[None, :, None], RESOLUTION)
    matrix = quadrature.quadratic_rows[0, 0].astype(np.float64) @ quadrature.incoming_features
    expected = closed_form_matrix(phase, RESOLUTION)
    # float32 factors: relative rounding 6e-8 per factor, summed over 5 features
    np.testing.assert_allclose(matrix, expected, rtol=2e-6, atol=0.0)


def test_source_function_of_gas_and_particles_is_the_closed_form_integral():
    rng = np.random.default_rng(3)
    res = RESOLUTION
    n_in = res.sphere_theta * res.sphere_phi
    n_r, n_mu_s, n_b = res.scattering_r, res.scattering_mu_s, 2
    phase = np.stack([np.stack([sampled(f)] * n_b, axis=-1) for f in (depolarised_rayleigh, hg)])
    incoming = rng.uniform(0.1, 1.0, (n_b, n_in, n_r * n_mu_s)).astype(np.float32)
    beta_s = np.array([[1e-5, 2e-5], [3e-6, 1e-6]])  # (n_s, n_b)
    node_density = np.array([[1.0, 0.8, 0.5, 0.1], [2.0, 0.5, 0.0, 0.0]])  # (n_s, n_r)
    got = source_function(phase_quadrature(phase, res), incoming, beta_s, node_density, res)
    got = got.reshape(n_r, res.density_theta, n_mu_s, res.density_phi, n_b)

    # S = sum_s w_s P_s @ L with w_s = n_s beta_s / sum_s n_s beta_s, in float64
    matrices = [closed_form_matrix(f, res) for f in (depolarised_rayleigh, hg)]
    light = incoming.astype(np.float64).reshape(n_b, n_in, n_r, n_mu_s)
    weights = node_density[:, :, None] * beta_s[:, None, :]
    weights /= weights.sum(axis=0, keepdims=True)
    for b in range(n_b):
        expected = sum(np.einsum("oi,irm->orm", m, light[b]) * weights[s, None, :, b, None]
                       for s, m in enumerate(matrices))
        expected = expected.reshape(res.density_theta, res.density_phi, n_r, n_mu_s)
        # the full matrix interpolates HG's samples linearly in the angle (1e-6 at 4097
        # samples) and both paths work in float32
        np.testing.assert_allclose(got[..., b], expected.transpose(2, 0, 3, 1), rtol=2e-5)


def test_wavelengths_with_the_same_particles_share_one_matrix_and_others_keep_their_own():
    # Earth's aerosol has one Henyey-Greenstein g at every wavelength; Mie particles change with
    # it. Each wavelength's integral is still its own phase function's closed-form matrix.
    n_in = RESOLUTION.sphere_theta * RESOLUTION.sphere_phi
    n_r, n_mu_s = RESOLUTION.scattering_r, RESOLUTION.scattering_mu_s
    g = [0.5, 0.8, 0.5]
    phase = np.stack([sampled(lambda c, g=g_b: henyey_greenstein(c, g)) for g_b in g],
                     axis=-1)[None]  # (1, n_angle, 3)
    quadrature = phase_quadrature(phase, RESOLUTION)
    assert quadrature.full_matrices.shape[0] == 2
    assert quadrature.full_index[0] == quadrature.full_index[2] != quadrature.full_index[1]

    incoming = np.random.default_rng(5).uniform(0.1, 1.0, (3, n_in, n_r * n_mu_s)
                                                ).astype(np.float32)
    got = source_function(quadrature, incoming, np.full((1, 3), 1e-5), np.ones((1, n_r)),
                          RESOLUTION).reshape(n_r, RESOLUTION.density_theta, n_mu_s,
                                              RESOLUTION.density_phi, 3)
    light = incoming.astype(np.float64).reshape(3, n_in, n_r, n_mu_s)
    for b, g_b in enumerate(g):
        matrix = closed_form_matrix(lambda c, g=g_b: henyey_greenstein(c, g), RESOLUTION)
        expected = np.einsum("oi,irm->orm", matrix, light[b]).reshape(
            RESOLUTION.density_theta, RESOLUTION.density_phi, n_r, n_mu_s)
        # as the test above: linear interpolation of the samples in angle, float32 products
        np.testing.assert_allclose(got[..., b], expected.transpose(2, 0, 3, 1), rtol=2e-5)


@pytest.mark.parametrize("absent", [(), (0,), (1,), (2,), (0, 2)])
def test_particles_absent_from_the_nodes_leave_the_source_the_closed_form_integral(absent):
    # three forward-scattering constituents, some with no density at any node of the call (a
    # cloud deck above or below these nodes), and incoming radiances far below anything
    # visible (1e-35, entered as 0): S = sum_s w_s P_s @ L over the present ones, in float64
    rng = np.random.default_rng(7)
    res = RESOLUTION
    n_in = res.sphere_theta * res.sphere_phi
    n_r, n_mu_s = res.scattering_r, res.scattering_mu_s
    g = (0.3, 0.6, 0.85)
    functions = [lambda c, g=g_s: henyey_greenstein(c, g) for g_s in g]
    phase = np.stack([sampled(f) for f in functions])[:, :, None]  # (3, n_angle, 1)
    incoming = rng.uniform(0.1, 1.0, (1, n_in, n_r * n_mu_s)).astype(np.float32)
    incoming[0, ::5] = 1e-35
    beta_s = np.array([[1e-5], [2e-5], [3e-6]])
    node_density = rng.uniform(0.2, 1.0, (3, n_r))
    node_density[list(absent)] = 0.0
    got = source_function(phase_quadrature(phase, res), incoming, beta_s, node_density, res)
    got = got.reshape(n_r, res.density_theta, n_mu_s, res.density_phi)

    light = incoming.astype(np.float64).reshape(n_in, n_r, n_mu_s)
    weights = node_density * beta_s
    weights /= weights.sum(axis=0, keepdims=True)
    expected = sum(np.einsum("oi,irm->orm", closed_form_matrix(f, res), light) * weights[s, None]
                   [..., None] for s, f in enumerate(functions))
    expected = expected.reshape(res.density_theta, res.density_phi, n_r, n_mu_s)
    # as above: HG's samples interpolated linearly in angle, float32 products; the dropped
    # radiances change S by < 1e-34 absolute
    np.testing.assert_allclose(got, expected.transpose(2, 0, 3, 1), rtol=2e-5, atol=1e-30)


@pytest.mark.parametrize("sphere", ["full", "coarse"])
def test_the_sphere_integral_keeps_a_cloud_phase_functions_first_moment(sphere):
    # For a normalised phase function of asymmetry g and a radiance field linear in the
    # direction, L(w) = w . d, the integral is closed: int p(v . w) (w . d) dw = g (v . d). It
    # is the first moment that carries a deck's diffuse light through it (diffusion goes with
    # 1 - g). On the full grid and on the coarse orders' sphere (tables.COARSE_SPHERE_THETA x
    # COARSE_SPHERE_PHI), for Henyey-Greenstein g = 0.85 (forward as a cloud droplet's phase
    # function once its diffraction peak is clipped), the error stays within 0.3 % of g:
    # 1 - g = 0.15 within 2 %. (Measured: 0.12 % full, 0.29 % coarse, 0.55 % on 24 x 12.)
    full = TableResolution()
    resolution = full
    if sphere == "coarse":
        resolution = coarse_resolution(full)
        assert (resolution.sphere_theta * resolution.sphere_phi
                < full.sphere_theta * full.sphere_phi)
    _, _, _, out, incoming, _ = sphere_grids(resolution)
    g = 0.85
    quadrature = phase_quadrature(sampled(lambda c: henyey_greenstein(c, g))[None, :, None],
                                  resolution)
    d = np.array([np.sin(0.5), 0.0, np.cos(0.5)])  # in the sun's vertical plane: L(w') = L(w)
    got = quadrature.full_matrices[0].astype(np.float64) @ (incoming @ d)
    assert np.abs(got - g * (out @ d)).max() < 0.003 * g
