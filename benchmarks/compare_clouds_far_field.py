"""The far field of cloud layers (independent columns, `transport._cloud_kernels._cross_columns`)
against the full march over the same patch, where both run (issue 19, whole-planet clouds).

A square patch of the layer over the north pole that spans one period of its coverage
variation (7.31 tiles) is seen by `--rays` x `--rays` parallel vertical rays spread evenly
across it (an orthographic view: the footprint of one pixel from space), looking down from
3 km above the layer's top and up from 2 m above the ground. The full march (the field with
a tiny pixel angle: never far) resolves every cloud; its mean over the rays is what a pixel
from space sees of that footprint. The far field (`FAR_START` = `FAR_END` = 0: always far)
gives every ray the mixture of cloudy and clear columns. Prints, per preset, view and band,
the mean radiance of the clouds' own light [W m^-2 sr^-1 nm^-1] and the mean transmittance
through them, both ways, and their differences.

With `--monte-carlo PATHS` the same rays also go through the whole scene (air, clouds,
ground) three ways: `render.scene.diffuse_radiance` with the full march, with the far field,
and `CloudMonteCarlo` (exact up to its noise, PATHS paths per ray and band); their means
over the rays are printed with the reference's standard error.

Run: python benchmarks/compare_clouds_far_field.py [--rays 48] [--sun-zenith 40]
                    [--presets cumulus stratocumulus] [--monte-carlo PATHS]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from skyscatter import api
from skyscatter.atmosphere._cloud_sampling import COVERAGE_TILE_RATIO, FAR_END, FAR_START
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.render.scene import diffuse_radiance, sun_direction
from skyscatter.transport import _cloud_kernels
from skyscatter.transport.cloud_monte_carlo import CloudMonteCarlo
from skyscatter.transport.clouds import cloud_lighting, kernel_arrays

WAVELENGTHS_NM = [450.0, 550.0, 650.0]


def march(field, solver, origins, rays, sun):
    """(radiance (n, n_wl), transmittance (n, n_wl)) of the clouds alone along the rays."""
    light = cloud_lighting(solver, field)
    arrays = (light.r_nodes, light.mu_nodes, light.sun_air, light.sky_down, light.ground_up,
              light.sun_toa)
    n, n_wl = rays.shape[0], field.wavelengths_nm.size
    radiance, transmittance = np.empty((n, n_wl)), np.empty((n, n_wl))
    unique, index = np.unique(origins, axis=0, return_inverse=True)
    for k, origin in enumerate(unique):
        chosen = np.flatnonzero(index.ravel() == k)
        r, t = np.empty((chosen.size, n_wl)), np.empty((chosen.size, n_wl))
        _cloud_kernels.march_clouds(np.ascontiguousarray(origin), np.ascontiguousarray(
            rays[chosen]), chosen, np.full(chosen.size, np.inf), field.bottom_radius_m, sun,
            kernel_arrays(field), arrays, r, t, np.empty(chosen.size),
            np.empty(chosen.size, dtype=np.bool_))
        radiance[chosen], transmittance[chosen] = r, t
    return radiance, transmittance


def geometry(layer, radius, rays_per_side):
    """(origins, directions) of the vertical rays from above and from below (docstring)."""
    side = COVERAGE_TILE_RATIO * layer.shape.scale_m * layer.shape.stretch
    offsets = (np.arange(rays_per_side) + 0.5) / rays_per_side * side - 0.5 * side
    x, y = np.meshgrid(offsets, offsets)
    ground = np.stack([x.ravel(), y.ravel(), np.full(x.size, radius)], axis=-1)
    # vertical at each ground point (the patch is 1/100 of a radian across: the local zenith)
    up = ground / np.linalg.norm(ground, axis=1, keepdims=True)
    above = ground + (layer.top_altitude_m + 3000.0) * up
    return (above, -up), (ground + 2.0 * up, up)


def scene(solver, fields, origins, rays, sun, paths, label):
    """Print the means over the rays of the whole scene's diffuse radiance: renderer with the
    march and with the far field, and the Monte Carlo reference (module docstring)."""
    started = time.perf_counter()
    means = {}
    for kind, field in fields.items():
        values = np.stack([diffuse_radiance(solver, origin, ray[None], sun, clouds=field)[0]
                           for origin, ray in zip(origins, rays, strict=True)])
        means[kind] = values.mean(axis=0)
    reference, error = CloudMonteCarlo(solver.profile, fields["march"], n_samples=paths,
                                       seed=19).radiance_with_error(origins, rays, sun)
    mean = reference.mean(axis=0)
    # the mean's standard error: the rays' errors are independent
    spread = np.sqrt((error**2).sum(axis=0)) / reference.shape[0]
    for k, wavelength in enumerate(WAVELENGTHS_NM):
        print(f"  scene {label} {wavelength:4.0f} nm: march {means['march'][k]:.4f} "
              f"({(means['march'][k] / mean[k] - 1) * 100:+.1f} %), far {means['far'][k]:.4f} "
              f"({(means['far'][k] / mean[k] - 1) * 100:+.1f} %), Monte Carlo {mean[k]:.4f} "
              f"+- {spread[k] / mean[k] * 100:.1f} %")
    print(f"  ({time.perf_counter() - started:.0f} s, {paths} paths per ray and band)",
          flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=96)
    parser.add_argument("--sun-zenith", type=float, default=40.0)
    parser.add_argument("--monte-carlo", type=int, default=0, metavar="PATHS")
    parser.add_argument("--presets", nargs="+", default=["cumulus", "stratocumulus",
                                                          "altocumulus", "cirrus"])
    args = parser.parse_args()
    atmosphere = api.load_atmosphere("earth")
    solver = api.load_solver(atmosphere, WAVELENGTHS_NM)
    radius = float(solver.profile.bottom_radius_m)
    sun = sun_direction(args.sun_zenith, 135.0)
    print(f"sun zenith {args.sun_zenith:g} deg; {args.rays}^2 vertical rays; bands "
          f"{WAVELENGTHS_NM} nm")
    print("preset         view   band   L march    L far      dL      T march  T far    dT")
    for name in args.presets:
        clouds = api.load_clouds(name)
        near = cloud_field(clouds, radius, solver.profile.wavelengths_nm, pixel_angle_rad=1e-12)
        far = dataclasses.replace(near, params=near.params.copy())
        far.params[:, FAR_START] = far.params[:, FAR_END] = 0.0
        fields = {"march": near, "far": far}
        started = time.perf_counter()
        for view, (origins, rays) in zip(("above", "below"), geometry(
                clouds.layers[0], radius, args.rays), strict=True):
            results = {kind: march(field, solver, origins, rays, sun)
                       for kind, field in fields.items()}
            for k, wavelength in enumerate(WAVELENGTHS_NM):
                lm, lf = (results[kind][0][:, k].mean() for kind in ("march", "far"))
                tm, tf = (results[kind][1][:, k].mean() for kind in ("march", "far"))
                print(f"{name:14s} {view:6s} {wavelength:4.0f}  {lm:9.4f}  {lf:9.4f}  "
                      f"{(lf / lm - 1) * 100:+6.1f}%  {tm:7.4f}  {tf:7.4f}  {tf - tm:+7.4f}")
            if args.monte_carlo:
                scene(solver, fields, origins, rays, sun, args.monte_carlo, f"{name} {view}")
        print(f"  ({time.perf_counter() - started:.1f} s)")


if __name__ == "__main__":
    main()
