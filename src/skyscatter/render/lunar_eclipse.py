r"""Sunlight on the Moon during a lunar eclipse: the geometric penumbra plus the light the Earth's
atmosphere refracts into the umbra, relative to full sunlight, per wavelength.

Seen from a point P behind the Earth (distance r from its centre), the Sun's disk has angular
radius s = asin(R_⊙/|S - P|) and its centre lies at angle ε from the Earth's centre; the Earth
with the refracting atmosphere (radius R + h_top) covers the angular radius β_top. All angles are
taken in the plane of P's sky (small angles: s ≈ 0.27°, β ≈ 1°, so the planar approximation
errs by ~β²/6 < 1e-4).

(a) Direct sunlight: the uniform solar disk minus the part hidden by the disk of radius β_top,

        C_direct = 1 - A(s, β_top, ε) / (π s²)

    with A the exact area of the lens where two circles of radii r_1, r_2 at distance d overlap
    (e.g. Weisstein, MathWorld "Circle-Circle Intersection"):

        A = r_1² acos((d² + r_1² - r_2²)/(2 d r_1)) + r_2² acos((d² + r_2² - r_1²)/(2 d r_2))
            - ½ √((-d + r_1 + r_2)(d + r_1 - r_2)(d - r_1 + r_2)(d + r_1 + r_2)).

    The solar disk is uniform here (no limb darkening): the partial-phase brightness is off by up
    to ~10 % of the local value near the umbra's edge, where the limb darkening matters most.

(b) Refracted sunlight (Link 1956, Bull. Astron. 20, 131; Link 1969, *Eclipse Phenomena in
    Astronomy*, Springer, ch. 2): P sees the atmosphere as a bright ring. The ray that reaches
    P from the ring at tangent altitude h (apparent radius β(h) = asin((R + h)/r) from the
    Earth's centre, position angle ψ) was bent towards the Earth by δ(h); before the bending it
    came from the sky point at radius b(h) = β(h) - δ(h) from the Earth's centre at the same ψ
    (b < 0: across the centre — the ray crossed the shadow axis). Radiance is conserved along
    the ray apart from the grazing transmittance T(h, λ), so the irradiance at P is

        C_refracted(λ) = 1/(π s²) ∫_0^{h_top} T(h, λ) β (dβ/dh) Ψ(h) dh,
        Ψ(h) = 2 acos(clip((b² + ε² - s²) / (2 |b| ε), -1, 1))

    where Ψ is the range of ψ over which the source point lies on the solar disk (law of
    cosines). For a point Sun this is the focusing factor: summed over the tangent
    altitudes that reach P at distance ρ from the axis, T (R + h) dh / (ρ dρ); the extended
    Sun removes its caustic at ρ = 0. The integral is a midpoint sum over altitude cells
    (default 100 m below 20 km, 1 km above, with exact β-widths of the cells).

The result C = C_direct + C_refracted multiplies the sunlit term of `moon.moon_disk_radiance`.
With T = 1 and δ = 0 it reduces to (a) for the bare Earth of radius R (a test checks this).
Ignored: the refracted light's different direction of incidence on the Moon (< 1.2°), the
ring's oblateness and the Earth's flattening, the refracted sun's chromatic dispersion (δ
does not depend on λ here: the callable returns one δ per altitude), and the light-time.

Public names: `DEFAULT_TOP_ALTITUDE_M`, `circle_overlap_area`, `default_altitude_edges_m`,
`eclipse_factor`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.astro.moon_phase import EARTH_SHADOW_RADIUS_M, SUN_RADIUS_M
from skyscatter.errors import InputError

__all__ = [
    "DEFAULT_TOP_ALTITUDE_M",
    "circle_overlap_area",
    "default_altitude_edges_m",
    "eclipse_factor",
]

DEFAULT_TOP_ALTITUDE_M = 100_000.0  # m; above it δ < 1e-7 rad (< 40 m at the Moon) and T ≈ 1


def circle_overlap_area(r1: ArrayLike, r2: ArrayLike, d: ArrayLike) -> np.ndarray:
    """Area of the overlap of two circles of radii r1, r2 whose centres are d apart (exact).

        A = r1² acos((d² + r1² - r2²)/(2 d r1)) + r2² acos((d² + r2² - r1²)/(2 d r2))
            - ½ √((-d + r1 + r2)(d + r1 - r2)(d - r1 + r2)(d + r1 + r2))

    for |r1 - r2| < d < r1 + r2; π min(r1, r2)² when one lies inside the other (d <= |r1 - r2|);
    0 when they are apart (d >= r1 + r2). Weisstein, "Circle-Circle Intersection", MathWorld.

    Parameters
    ----------
    r1, r2, d : array_like, broadcast to S
        Radii (>= 0) and the distance between the centres (>= 0), any one length unit.

    Returns
    -------
    ndarray, shape S
        Area, in that unit squared.
    """
    r1, r2, d = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (r1, r2, d)))
    area = np.zeros(r1.shape)
    small = np.minimum(r1, r2)
    inside = d <= np.abs(r1 - r2)
    area[inside] = np.pi * small[inside] ** 2
    lens = ~inside & (d < r1 + r2)
    a, b, c = r1[lens], r2[lens], d[lens]
    term1 = a * a * np.arccos(np.clip((c * c + a * a - b * b) / (2.0 * c * a), -1.0, 1.0))
    term2 = b * b * np.arccos(np.clip((c * c + b * b - a * a) / (2.0 * c * b), -1.0, 1.0))
    kite = (-c + a + b) * (c + a - b) * (c - a + b) * (c + a + b)
    area[lens] = term1 + term2 - 0.5 * np.sqrt(np.maximum(kite, 0.0))
    return area


def default_altitude_edges_m(top_altitude_m: float = DEFAULT_TOP_ALTITUDE_M) -> np.ndarray:
    """Edges of the tangent-altitude cells of (b): 100 m steps to 20 km, 1 km steps above. [m]

    Near the ground the source radius b(h) changes by ~2.6e-4 rad per 100 m (δ/H with
    δ(0) ≈ 0.02 rad, H = 8 km), ~18 cells across the solar disk (2 s = 9.3e-3 rad). Against
    5 m cells (exponential test atmosphere, 0 <= ρ <= ρ_p): <= 1.6 % at 550-700 nm, 3 % at
    450 nm, 2e-5 of full sunlight absolute; 50 m / 500 m cells are no better.
    """
    top = float(top_altitude_m)
    low = np.arange(0.0, min(top, 20_000.0), 100.0)
    high = np.arange(20_000.0, top, 1000.0)
    return np.unique(np.concatenate([low, high, [top]]))


def eclipse_factor(points_geocentric_m: ArrayLike, sun_geocentric_m: ArrayLike,
                   grazing_transmittance: Callable[[np.ndarray], np.ndarray],
                   grazing_deflection_rad: Callable[[np.ndarray], np.ndarray], *,
                   earth_radius_m: float = EARTH_SHADOW_RADIUS_M,
                   sun_radius_m: float = SUN_RADIUS_M,
                   top_altitude_m: float = DEFAULT_TOP_ALTITUDE_M,
                   altitude_edges_m: ArrayLike | None = None) -> np.ndarray:
    """Sunlight reaching points behind the Earth, relative to full sunlight: C = (a) + (b).

    See the module docstring for the model (geometric penumbra of a uniform Sun behind the
    Earth of radius R + h_top, plus the refracted light through tangent altitudes
    0..h_top, Link 1956/1969).

    Parameters
    ----------
    points_geocentric_m : array_like, shape (n, 3)
        Points on the Moon, relative to the Earth's centre; farther than R + h_top. [m]
    sun_geocentric_m : array_like, shape (3,)
        The Sun's centre relative to the Earth's centre, same frame. [m]
    grazing_transmittance : callable
        `T(tangent_altitudes_m (k,)) -> (k, n_wl)`: transmittance [-] of the whole grazing
        path of the ray whose lowest point is at that altitude (both halves), e.g. from the
        caller's atmosphere. Return zeros for no atmosphere / opaque clouds below some height.
    grazing_deflection_rad : callable
        `δ(tangent_altitudes_m (k,)) -> (k,)`: total refraction angle of that ray, towards
        the Earth, >= 0. [rad]
    earth_radius_m : float
        Radius R of the spherical Earth (tangent altitude 0); default 6367.5 km (45° latitude,
        as `astro.moon_phase`); pass the atmosphere's bottom radius. [m]
    sun_radius_m : float
        Solar radius; 6.957e8 m (IAU 2015 B3). [m]
    top_altitude_m : float
        h_top: top of the refracting atmosphere, >= 0; the Earth + atmosphere up to it is the
        occulter of (a). [m]
    altitude_edges_m : array_like or None
        Cell edges of the altitude integral, ascending from 0 to h_top; default
        `default_altitude_edges_m(top_altitude_m)`. [m]

    Returns
    -------
    ndarray, shape (n, n_wl)
        C: 1 in full sunlight, the uniform-disk fraction in the penumbra, ~1e-4..1e-3 of full
        sunlight in the red at the umbra's centre for a clear atmosphere. [-]
    """
    p = np.asarray(points_geocentric_m, dtype=np.float64)
    sun = np.asarray(sun_geocentric_m, dtype=np.float64)
    if p.ndim != 2 or p.shape[-1] != 3 or sun.shape != (3,):
        raise InputError(f"points_geocentric_m must be (n, 3) and sun_geocentric_m (3,); got "
                         f"{p.shape} and {sun.shape}", key="points_geocentric_m", value=p.shape,
                         allowed="(n, 3) and (3,)")
    top = float(top_altitude_m)
    if not (np.isfinite(top) and top >= 0.0):
        raise InputError(f"top_altitude_m = {top_altitude_m!r} must be >= 0 [m]",
                         key="top_altitude_m", value=top_altitude_m, allowed=">= 0 [m]")
    edges = (default_altitude_edges_m(top) if altitude_edges_m is None
             else np.asarray(altitude_edges_m, dtype=np.float64))
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0.0) or edges[0] < 0.0:
        raise InputError("altitude_edges_m must ascend from >= 0 with at least two edges",
                         key="altitude_edges_m", value=edges, allowed="ascending, >= 0 [m]")
    radius = float(earth_radius_m)
    r = np.linalg.norm(p, axis=-1)
    if np.any(r <= radius + max(top, edges[-1])):
        raise InputError("points_geocentric_m must lie above the atmosphere "
                         f"(> {radius + top:g} m from the Earth's centre)",
                         key="points_geocentric_m", value=float(r.min()),
                         allowed=f"> {radius + top:g} m")
    to_sun = sun - p
    d_sun = np.linalg.norm(to_sun, axis=-1)
    s = np.arcsin(sun_radius_m / d_sun)  # (n,)
    # ε: angle at P between the Earth's centre (-p) and the Sun's centre (to_sun)
    eps = np.arctan2(np.linalg.norm(np.cross(-p, to_sun), axis=-1),
                     np.einsum("ij,ij->i", -p, to_sun))
    disk_area = np.pi * s * s
    beta_top = np.arcsin((radius + top) / r)
    direct = 1.0 - circle_overlap_area(s, beta_top, eps) / disk_area

    mids = 0.5 * (edges[1:] + edges[:-1])
    transmittance = np.asarray(grazing_transmittance(mids), dtype=np.float64)
    if transmittance.ndim != 2 or transmittance.shape[0] != mids.size:
        raise InputError(f"grazing_transmittance must return ({mids.size}, n_wl); got "
                         f"{transmittance.shape}", key="grazing_transmittance",
                         value=transmittance.shape, allowed="(k, n_wl)")
    result = np.repeat(direct[:, None], transmittance.shape[1], axis=1)
    if not np.any(transmittance > 0.0):
        return result
    deflection = np.asarray(grazing_deflection_rad(mids), dtype=np.float64).reshape(mids.shape)
    # Only points that can see refracted sunlight: the source circles have |b| <= β_top (δ >= 0),
    # so none reaches the solar disk when ε >= β_top + s.
    rows = np.flatnonzero(eps < beta_top + s)
    if rows.size == 0:
        return result
    r, e, s2 = r[rows, None], eps[rows, None], s[rows, None] ** 2
    beta_edges = np.arcsin((radius + edges)[None, :] / r)  # (m, k + 1)
    area = 0.5 * np.diff(beta_edges * beta_edges, axis=1)  # β dβ of each cell, exact
    b = beta_edges[:, 1:] + beta_edges[:, :-1]  # in place below: b = |β_mid - δ|
    b *= 0.5
    b -= deflection[None, :]
    np.abs(b, out=b)
    # cos(Ψ/2) = (b² + ε² - s²) / (2 b ε); b ε = 0: the source circle is a point (or P is on
    # the axis): Ψ = 2π if it lies on the disk (b² + ε² < s²), else 0.
    numerator = b * b
    numerator += e * e - s2
    b *= 2.0 * e
    cos_half = np.where(numerator < 0.0, -1.0, 1.0)
    np.divide(numerator, b, out=cos_half, where=b > 0.0)
    np.clip(cos_half, -1.0, 1.0, out=cos_half)
    arc = np.arccos(cos_half, out=cos_half)  # Ψ/2
    area *= arc
    result[rows] += (area @ transmittance) * (2.0 / disk_area[rows, None])
    return result
