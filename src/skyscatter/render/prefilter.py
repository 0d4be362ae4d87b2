"""A specular mip chain of a cube map, prefiltered with the GGX distribution.

The first sum of Karis's split-sum approximation (Karis 2013, "Real Shading in Unreal Engine
4", SIGGRAPH course "Physically Based Shading in Theory and Practice", eqs. 4-5), which engines
store as the mip levels of a cube map: with n = v = r,

    L_k(n) = int L(l) D(h) (n . l)+ dl / int D(h) (n . l)+ dl,    h = (n + l) / |n + l|

(Karis's estimator sum L(l_i) (n . l_i) / sum (n . l_i), with l_i drawn with the pdf
D(h) (n . h) / (4 v . h) = D(h) / 4 at n = v, is a Monte Carlo estimate of this ratio; here
both integrals are sums over the map's texels with their exact solid angles, without noise).
D is GGX (Trowbridge & Reitz 1975; Walter et al. 2007, "Microfacet models for refraction
through rough surfaces", EGSR, eq. 33):

    D(h) = alpha^2 / (pi ((n . h)^2 (alpha^2 - 1) + 1)^2),    (n . h)^2 = (1 + n . l) / 2

with alpha = roughness^2 (Karis's remapping) and roughness = k / (levels - 1) at level k.
Level 0 is the map; level k has faces of face / 2^k texels and filters the map itself, or,
where that would sum more than `PAIR_BUDGET` texel pairs, the map averaged over blocks of
2^j x 2^j texels (weighted by their solid angles, so that int L dOmega is kept), j the
smallest that keeps within the budget, at most k - 1 (twice the level's resolution). At
roughness 1, D = 1 / pi everywhere: the top level is E(n) / pi, the map's cosine-weighted
irradiance over pi.

Cost: level 1 sums 6 (face / 2)^2 x 6 face^2 texel pairs (2.4e9 at a face of 128: the chain
takes 11 s on 2 cores).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from skyscatter.render.cube_map import CubeMapCamera

__all__ = ["PAIR_BUDGET", "ggx_prefilter", "mip_roughness", "prefiltered_mips"]

PAIR_BUDGET = 2.5e9  # texel pairs a level may sum before its source is averaged down


def mip_roughness(levels: int) -> list[float]:
    """Roughness k / (levels - 1) of each level k (module docstring)."""
    return [k / (levels - 1) for k in range(levels)]


@njit(cache=True, parallel=True)
def ggx_prefilter(normals: np.ndarray, directions: np.ndarray, solid_angles: np.ndarray,
                  radiance: np.ndarray, alpha: float) -> np.ndarray:
    """L_k (m, c) at unit `normals` (m, 3) of the radiance (k, c) arriving along unit
    `directions` (k, 3) over `solid_angles` (k,) [sr], GGX of `alpha` > 0 (module docstring)."""
    a2 = alpha * alpha
    out = np.zeros((normals.shape[0], radiance.shape[1]))
    for m in prange(normals.shape[0]):
        total = 0.0
        for k in range(directions.shape[0]):
            cos_nl = (normals[m, 0] * directions[k, 0] + normals[m, 1] * directions[k, 1]
                      + normals[m, 2] * directions[k, 2])
            if cos_nl <= 0.0 or solid_angles[k] == 0.0:
                continue
            q = 0.5 * (1.0 + cos_nl) * (a2 - 1.0) + 1.0
            weight = a2 / (np.pi * q * q) * cos_nl * solid_angles[k]
            total += weight
            for c in range(radiance.shape[1]):
                out[m, c] += weight * radiance[k, c]
        if total > 0.0:
            for c in range(radiance.shape[1]):
                out[m, c] /= total
    return out


def _block_average(rgb: np.ndarray, solid_angles: np.ndarray,
                   factor: int) -> np.ndarray:
    """The image (h, w, c) averaged over `factor` x `factor` blocks, weighted by the pixels'
    `solid_angles` (h, w); blocks of no solid angle (off the faces) are 0."""
    h, w, c = rgb.shape
    weights = solid_angles.reshape(h // factor, factor, w // factor, factor)
    sums = np.einsum("iajb,iajbc->ijc", weights, rgb.reshape(h // factor, factor,
                                                             w // factor, factor, c))
    total = weights.sum(axis=(1, 3))[..., None]
    return np.divide(sums, total, out=np.zeros_like(sums), where=total > 0.0)


def prefiltered_mips(rgb: np.ndarray, camera: CubeMapCamera, levels: int) -> list[np.ndarray]:
    """The `levels` images (face / 2^k texels a face, `camera`'s layout) of the mip chain of
    the cube map `rgb` (h, w, c) rendered by `camera`; level 0 is `rgb` itself. The face must
    be divisible by 2^(levels - 1)."""
    chain = [np.asarray(rgb, dtype=np.float64)]
    source_omega = camera.pixel_solid_angles()
    for k, roughness in enumerate(mip_roughness(levels)[1:], start=1):
        target = CubeMapCamera(camera.face >> k, camera.layout)
        j = 0
        while j < k - 1 and 36.0 * target.face**2 * (camera.face >> j) ** 2 > PAIR_BUDGET:
            j += 1
        source_camera = CubeMapCamera(camera.face >> j, camera.layout)
        source = _block_average(chain[0], source_omega, 1 << j)
        normals, valid = target.directions()
        directions, _ = source_camera.directions()
        filtered = ggx_prefilter(normals[valid], directions.reshape(-1, 3),
                                 source_camera.pixel_solid_angles().ravel(),
                                 source.reshape(-1, source.shape[-1]), roughness**2)
        level = np.zeros(normals.shape[:2] + (source.shape[-1],))
        level[valid] = filtered
        chain.append(level)
    return chain
