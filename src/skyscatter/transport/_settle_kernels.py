"""Kernel of `transport.clouds`' adaptive refinement: a pixel between marched ones takes their
mean where their radiance agrees (`adaptive_pixels`)."""

from __future__ import annotations

from numba import njit, prange

__all__ = ["settle_mean"]


@njit(cache=True, parallel=True)
def settle_mean(targets, neighbours, behind, tolerance, transmittance, added, hit, agree):
    """For each target ray: its neighbours' radiances over its own background,
    T behind[target] + A, per band; where they all met a cloud or all missed one and spread by
    at most `tolerance` times their mean in every band, the target's T, A and hit become the
    neighbours' mean (T and A (n, n_wl) float32, hit (n,) bool, in place); agree (m,) says
    where."""
    n_wl = behind.shape[1]
    k_count = neighbours.shape[1]
    for i in prange(targets.size):
        target = targets[i]
        first_hit = hit[neighbours[i, 0]]
        ok = True
        for k in range(1, k_count):
            ok &= hit[neighbours[i, k]] == first_hit
        band = 0
        while ok and band < n_wl:
            low, high, total = 1e300, -1e300, 0.0
            for k in range(k_count):
                j = neighbours[i, k]
                value = transmittance[j, band] * behind[target, band] + added[j, band]
                low, high, total = min(low, value), max(high, value), total + value
            ok = high - low <= tolerance * abs(total / k_count)
            band += 1
        agree[i] = ok
        if not ok:
            continue
        for band in range(n_wl):
            t_sum, a_sum = 0.0, 0.0
            for k in range(k_count):
                t_sum += transmittance[neighbours[i, k], band]
                a_sum += added[neighbours[i, k], band]
            transmittance[target, band] = t_sum / k_count
            added[target, band] = a_sum / k_count
        hit[target] = first_hit
