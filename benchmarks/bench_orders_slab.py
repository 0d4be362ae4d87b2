"""Estimate: scattering orders a thick layer needs when the orders are summed one by one.

A plane-parallel slab (optical depth tau, single-scattering albedo omega, Henyey-Greenstein g,
Lambertian ground of albedo 0.1) under a sun of zenith cosine mu0, solved order by order:
azimuth-averaged intensities on 2 x 24 Gauss streams, 0.02-thick sub-layers with the source
constant in each (the formal solution I = I e^(-dtau/mu) + J (1 - e^(-dtau/mu))), the
azimuth-integrated phase matrix normalised row by row (as the tables' sphere integral is).
Prints, per layer preset, the orders after which the rest of the sum holds less than 0.5 % of
the diffuse flux at the ground and of the zenith radiance there, and the ratio of successive
orders at the end (the geometric tail a convergence criterion can extrapolate), plain and after
a delta scaling with the forward fraction f = g^2 (tau' = (1 - omega f) tau,
omega' = (1 - f) omega / (1 - omega f), g' = (g - f) / (1 - f); Joseph et al. 1976,
J. Atmos. Sci. 33, 2452, doi:10.1175/1520-0469(1976)033<2452:TDEAFR>2.0.CO;2).

A model of the layer alone (no air, no sphericity), for choosing `[tables] orders`; the tables'
own truncation error is measured by bench_orders.py. Run: python benchmarks/bench_orders_slab.py
(about a minute on 2 cores).
"""

from __future__ import annotations

import numpy as np

STREAMS = 24       # Gauss nodes per hemisphere
SUB_LAYER = 0.02   # optical thickness of a sub-layer
GROUND_ALBEDO = 0.1
TAIL = 0.005       # the rest of the sum that is left out
# (preset, tau, omega, g): the layer at its reference wavelength; mars-dust-storm's dust at
# 880 nm, where it absorbs least (omega 0.973, g 0.697 from its Mie table; 0.81 at 550 nm).
LAYERS = [("earth-overcast", 20.0, 1.0, 0.863), ("earth-fog", 5.868, 1.0, 0.863),
          ("mars-dust-storm", 5.0, 0.973, 0.697)]


def henyey_greenstein(cos_angle: np.ndarray, g: float) -> np.ndarray:
    """Henyey & Greenstein (1941) phase function [sr^-1]."""
    return (1.0 - g * g) / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * cos_angle) ** 1.5)


def azimuth_integrated(mu_out: np.ndarray, mu_in: np.ndarray, g: float) -> np.ndarray:
    """int_0^2pi p(mu_out, mu_in, phi) dphi, (n_out, n_in) [-], on 256 azimuth midpoints."""
    phi = (np.arange(256) + 0.5) * np.pi / 256
    sines = np.sqrt(1.0 - mu_out[:, None] ** 2) * np.sqrt(1.0 - mu_in[None, :] ** 2)
    cos_angle = mu_out[:, None, None] * mu_in[None, :, None] + sines[..., None] * np.cos(phi)
    return 2.0 * np.pi * henyey_greenstein(cos_angle, g).mean(axis=-1)


def orders(tau: float, omega: float, g: float, mu0: float) -> tuple[np.ndarray, np.ndarray]:
    """Diffuse ground flux and zenith radiance of each order (per unit solar flux)."""
    x, w = np.polynomial.legendre.leggauss(STREAMS)
    mu, weight = 0.5 * (x + 1.0), 0.5 * w
    streams = np.concatenate([-mu, mu])  # down, then up
    weights = np.concatenate([weight, weight])
    matrix = azimuth_integrated(streams, streams, g)
    matrix /= (matrix * weights).sum(axis=1, keepdims=True)
    n = int(round(tau / SUB_LAYER))
    middle = (np.arange(n) + 0.5) * tau / n
    decay = np.exp(-(tau / n) / mu)
    # order 1: the direct beam (flux 1 normal to it) scattered, azimuth-averaged:
    # J = omega int p dphi / (2 pi) e^(-tau/mu0); then J = omega sum_j w_j P_ij I_j
    source = omega * azimuth_integrated(streams, np.array([-mu0]), g)[:, 0] / (2.0 * np.pi)
    source = source[None, :] * np.exp(-middle / mu0)[:, None]
    ground = GROUND_ALBEDO / np.pi * mu0 * np.exp(-tau / mu0)
    flux, zenith = [], []
    while len(flux) < 20 or flux[-1] > 1e-7 * max(flux):
        down = np.zeros((n + 1, STREAMS))
        for k in range(n):
            down[k + 1] = down[k] * decay + source[k, :STREAMS] * (1.0 - decay)
        up = np.zeros((n + 1, STREAMS))
        up[n] = ground
        for k in range(n - 1, -1, -1):
            up[k] = up[k + 1] * decay + source[k, STREAMS:] * (1.0 - decay)
        flux.append(2.0 * np.pi * np.sum(weight * mu * down[n]))
        zenith.append(down[n, -1])
        mean = np.concatenate([down[1:] + down[:-1], up[1:] + up[:-1]], axis=1) / 2.0
        source = omega * mean @ (matrix * weights).T
        ground = GROUND_ALBEDO / np.pi * flux[-1]
    return np.array(flux), np.array(zenith)


def needed(series: np.ndarray) -> int:
    """Orders after which the rest of the sum is below TAIL of the whole."""
    rest = series.sum() - np.cumsum(series)
    return int(np.argmax(rest < TAIL * series.sum())) + 1


def main() -> None:
    print(f"orders until the rest is < {TAIL:.1%} of the diffuse ground flux / zenith radiance")
    for name, tau, omega, g in LAYERS:
        for mu0 in (1.0, 0.5):
            for scaled in (False, True):
                t, o, a = tau, omega, g
                if scaled:
                    f = g * g
                    t, o, a = (1 - omega * f) * tau, (1 - f) * omega / (1 - omega * f), (
                        (g - f) / (1 - f))
                flux, zenith = orders(t, o, a, mu0)
                kind = "delta f=g^2" if scaled else "plain"
                print(f"{name:16s} tau {tau:6.3f} mu0 {mu0}: {kind:11s} flux "
                      f"{needed(flux):4d}, zenith {needed(zenith):4d}; last ratio "
                      f"{flux[-1] / flux[-2]:.4f} ({flux.size} orders summed)")


if __name__ == "__main__":
    main()
