"""The sphere integral of the tables' orders >= 2: phase matrices and the source function.

J_n(x, v) = sum_s n_s beta_s,s int_{4 pi} p_s(v . w) L_{n-1}(x, w) dw is a matrix product on a
grid of n_in incoming directions w_i (half a sphere, its mirror image about the sun's vertical
plane added) and n_out outgoing directions v_o: P_s[o, i] = (p_s(v_o . w_i) + p_s(v_o . w_i'))
dOmega_i, each row normalised to sum to 1, so that the discrete integral conserves energy even
where it does not resolve a forward peak (`tables` module docstring).

A phase function that is a polynomial of degree 2 in the cosine of the scattering angle,
p(c) = a + b c^2 (Rayleigh scattering with any depolarisation, Chandrasekhar 1950, "Radiative
Transfer", ch. 1; isotropic scattering, b = 0), gives a matrix of rank 5: with the mirror image
w' = (x, -y, z), p(v . w) + p(v . w') = 2a + 2b (v_x^2 w_x^2 + v_y^2 w_y^2 + v_z^2 w_z^2
+ 2 v_x v_z w_x w_z), the terms odd in w_y cancelling. Such a constituent's integral is taken
through those 5 features, exactly the same matrix (rows normalised on the same grid) for
5 (n_in + n_out) instead of n_in n_out operations per column. Every planet's gas is such a
constituent; particles keep the full matrix.

Public names: `PhaseQuadrature`, `phase_quadrature`, `source_function`, `sphere_grids`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from skyscatter.transport import _table_build_kernels

if TYPE_CHECKING:
    from skyscatter.transport.tables import TableResolution

__all__ = ["PhaseQuadrature", "phase_quadrature", "source_function", "sphere_grids"]

# A sampled phase function is taken as a + b c^2 when that fit is off by at most this share of
# its largest value anywhere: float64 round-off of Rayleigh's closed form is 1e-16; the full
# matrix interpolates the samples linearly in the angle, within 2e-7 of the closed form.
QUADRATIC_TOLERANCE = 1e-9
# Weighted incoming radiances below this [W m^-2 nm^-1 sr^-1] (30 orders of magnitude below a
# daylit sky's ~0.1) enter the source as 0: their float32 products with the phase matrices
# (entries >= ~1e-7) would be subnormal numbers, which the CPU multiplies 5-10 x slower. A
# stratus deck's light far below and above it has many: its source product took 0.10 s a
# wavelength instead of 0.014 s (`earth-overcast`, second order, 2 cores).
NEGLIGIBLE_RADIANCE = 1e-30


class PhaseQuadrature(NamedTuple):
    """The phase matrices of one wavelength batch (n_b wavelengths): the full matrices of the
    constituents `full` (indices into the scattering constituents), (n_u, n_out, n_full n_in)
    float32 side by side, one per distinct set of their phase functions, wavelength b's
    `full_matrices[full_index[b]]` (Earth's aerosol has one Henyey-Greenstein g at every
    wavelength: one matrix, 2 instead of 30 MiB), and for the constituents `quadratic` (p = a
    + b c^2) the rows `quadratic_rows` (n_q, n_b, n_out, 5) float32, features times
    coefficients over the row sums, and the incoming features times solid angle
    `incoming_features` (5, n_in) float32 (module docstring)."""

    full: np.ndarray
    full_matrices: np.ndarray
    full_index: np.ndarray
    quadratic: np.ndarray
    quadratic_rows: np.ndarray
    incoming_features: np.ndarray


def sphere_grids(resolution: TableResolution) -> tuple[np.ndarray, ...]:
    """(theta_in, phi_in, solid_angle_in (n_in,), out directions (n_out, 3), in directions and
    their mirror images (n_in, 3) each) in a frame whose x-z plane holds the sun."""
    theta_in = (np.arange(resolution.sphere_theta) + 0.5) * np.pi / resolution.sphere_theta
    phi_in = (np.arange(resolution.sphere_phi) + 0.5) * np.pi / resolution.sphere_phi
    theta_out = np.linspace(0.0, np.pi, resolution.density_theta)
    phi_out = np.linspace(0.0, np.pi, resolution.density_phi)

    def directions(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
        t, p = np.meshgrid(theta, phi, indexing="ij")
        return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)],
                        axis=-1).reshape(-1, 3)

    solid = (np.sin(theta_in)[:, None] * (np.pi / resolution.sphere_theta)
             * (np.pi / resolution.sphere_phi) * np.ones(resolution.sphere_phi)).reshape(-1)
    incoming = directions(theta_in, phi_in)
    mirrored = incoming * np.array([1.0, -1.0, 1.0])
    return theta_in, phi_in, solid, directions(theta_out, phi_out), incoming, mirrored


def phase_quadrature(phase: np.ndarray, resolution: TableResolution) -> PhaseQuadrature:
    """The sphere integral of phase functions `phase` (n_s, n_angle, n_b) sampled at angles
    uniform over [0, pi] (`scatterers.sample_phase_functions`), on the grids of `resolution`
    (module docstring)."""
    _, _, solid, out, incoming, mirrored = sphere_grids(resolution)
    coefficients, quadratic = _quadratic_fits(phase)
    full = np.flatnonzero(~quadratic)
    full_phase = phase[full]
    distinct, full_index = _distinct_wavelengths(full_phase)
    matrices = _table_build_kernels.phase_matrices(  # (n_full, n_u, n_out, n_in)
        np.ascontiguousarray(full_phase[:, :, distinct]), np.ascontiguousarray(out @ incoming.T),
        np.ascontiguousarray(out @ mirrored.T), solid)
    n_full, n_u, n_out, n_in = matrices.shape
    full_matrices = np.ascontiguousarray(matrices.transpose(1, 2, 0, 3)).reshape(
        n_u, n_out, n_full * n_in)
    out_features, in_features = _features(out), _features(incoming)
    in_weighted = in_features * solid[None, :]  # (5, n_in)
    # the features' coefficients: 2a for the constant, 2b for the four quadratic ones
    scale = 2.0 * np.concatenate([coefficients[quadratic][..., :1],
                                  np.repeat(coefficients[quadratic][..., 1:], 4, axis=-1)],
                                 axis=-1)  # (n_q, n_b, 5)
    rows = out_features.T[None, None] * scale[:, :, None, :]  # (n_q, n_b, n_out, 5)
    row_sums = rows @ in_weighted.sum(axis=1)  # (n_q, n_b, n_out)
    return PhaseQuadrature(
        full=full, full_matrices=full_matrices, full_index=full_index,
        quadratic=np.flatnonzero(quadratic),
        quadratic_rows=(rows / row_sums[..., None]).astype(np.float32),
        incoming_features=in_weighted.astype(np.float32))


def source_function(quadrature: PhaseQuadrature, incoming: np.ndarray, beta_s: np.ndarray,
                    node_density: np.ndarray, resolution: TableResolution) -> np.ndarray:
    """Source function S = J / beta_s on the scattering-density grid, laid out for
    `multiple_scattering_table`: (n_r, n_theta, n_mu_s * n_phi * n_b) float32 (axes r, theta,
    then mu_s, phi, wavelength flattened).

    J = sum_s n_s beta_s (P_s @ L) and beta_s = sum_s n_s beta_s at each r node (densities
    `node_density` (n_s, n_r)), so S is the phase-weighted mean incoming radiance, smooth in r;
    the kernel multiplies it by the exact scattering coefficient along each ray. Where no
    constituent scatters (above the profile), the constituents are weighted by beta_s alone.
    incoming: (n_b, n_in, n_r n_mu_s); beta_s: (n_s, n_b). The r nodes may be any run of the
    table's (`node_density` and `incoming` of the same nodes), so that an order's source is
    built a few nodes at a time (`tables.precompute_tables`)."""
    n_s, n_b = beta_s.shape
    n_in = incoming.shape[1]
    n_r, n_mu_s = node_density.shape[1], resolution.scattering_mu_s
    n_theta, n_phi = resolution.density_theta, resolution.density_phi
    weights = node_density[:, :, None] * beta_s[:, None, :]  # (n_s, n_r, n_b)
    empty = weights.sum(axis=0) <= 0.0
    weights = np.where(empty[None], beta_s[:, None, :], weights)
    weights = (weights / weights.sum(axis=0, keepdims=True)).astype(np.float32)
    incoming = incoming.reshape(n_b, n_in, n_r, n_mu_s)
    full, quadratic = quadrature.full, quadrature.quadratic
    source = np.empty((n_r, n_theta, n_mu_s, n_phi, n_b), dtype=np.float32)
    for b in range(n_b):
        product = np.zeros((n_theta * n_phi, n_r, n_mu_s), dtype=np.float32)
        # the full constituents present at these nodes: a cloud deck is absent from most
        present = np.flatnonzero(weights[full, :, b].max(axis=1, initial=0.0) > 0.0)
        if present.size:
            # one product for the run of full constituents from the first present to the last:
            # [P_i .. P_j] @ [w_i L; ..; w_j L], the weights per r applied to the incoming
            # radiance (the smaller operand)
            first, stop = present[0], present[-1] + 1
            weighted = (weights[full[first:stop]][:, None, :, b, None] * incoming[b][None]
                        ).reshape((stop - first) * n_in, -1)
            weighted[np.abs(weighted) < NEGLIGIBLE_RADIANCE] = 0.0
            matrices = quadrature.full_matrices[quadrature.full_index[b]]
            product += (matrices[:, first * n_in:stop * n_in] @ weighted).reshape(product.shape)
        if quadratic.size:
            # the weights per r commute with the projection on the incoming features
            projected = (quadrature.incoming_features @ incoming[b].reshape(n_in, -1)
                         ).reshape(5, n_r, n_mu_s)
            for q, s in enumerate(quadratic):
                product += (quadrature.quadratic_rows[q, b]
                            @ (projected * weights[s, None, :, b, None]).reshape(5, -1)
                            ).reshape(product.shape)
        source[..., b] = product.reshape(n_theta, n_phi, n_r, n_mu_s).transpose(2, 0, 3, 1)
    return source.reshape(n_r, n_theta, -1)


def _distinct_wavelengths(phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the wavelengths whose phase functions, `phase` (n, n_angle, n_b), are each set's first,
    and for every wavelength the index of its set among them)."""
    n_b = phase.shape[2]
    rows = phase.transpose(2, 0, 1).reshape(n_b, -1)
    _, first, which = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    return first, which.reshape(n_b)


def _features(directions: np.ndarray) -> np.ndarray:
    """(5, n): 1, x^2, y^2, z^2 and sqrt(2) x z of unit `directions` (n, 3), whose products
    for v and w and its mirror image sum p(v . w) + p(v . w') of p = a + b c^2 (module
    docstring) with the coefficients (2a, 2b, 2b, 2b, 2b)."""
    x, y, z = directions.T
    return np.stack([np.ones_like(x), x * x, y * y, z * z, np.sqrt(2.0) * x * z])


def _quadratic_fits(phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((a, b) (n_s, n_b, 2), and per constituent (n_s,) whether p = a + b c^2 holds within
    QUADRATIC_TOLERANCE of its largest value at every sample and wavelength) for `phase`
    (n_s, n_angle, n_b) sampled at angles uniform over [0, pi]: least squares in c^2."""
    n_s, n_angle, n_b = phase.shape
    c2 = np.cos(np.linspace(0.0, np.pi, n_angle)) ** 2
    design = np.stack([np.ones(n_angle), c2], axis=1)  # (n_angle, 2)
    samples = phase.transpose(1, 0, 2).reshape(n_angle, -1)
    fit = np.linalg.lstsq(design, samples, rcond=None)[0]  # (2, n_s n_b)
    residual = np.abs(design @ fit - samples).max(axis=0)
    largest = np.abs(samples).max(axis=0)
    holds = (residual <= QUADRATIC_TOLERANCE * largest).reshape(n_s, n_b).all(axis=1)
    return fit.T.reshape(n_s, n_b, 2), holds
