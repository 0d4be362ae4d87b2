"""Compare the cloud renderer with the Monte Carlo reference through the same clouds (issue 19
section 3): a single cumulus, a cumulus field and a stratus deck seen from the ground, and the
cumulus field seen from 6 km. Prints, per case and band, the image mean of both, their
relative difference, the median and 90th percentile of the per-pixel relative error, and the
Monte Carlo's own noise (median relative standard error); writes the three images per case
(renderer, Monte Carlo, relative error) to a figure.

Both compute the diffuse radiance (sky, clouds and ground, the sun disk left out) of the `earth`
atmosphere on 3 bands, the sun 40 deg from the zenith: the renderer from the tables
(`render.scene.diffuse_radiance` with clouds), the reference by `CloudMonteCarlo`.

Run: python benchmarks/compare_clouds_montecarlo.py [--paths N] [--size N] [--figure PNG]
                                                    [--cases 0,2] [--reference-cache DIR]
(--reference-cache keeps each case's Monte Carlo image in DIR and reuses it when the size and
paths match: the renderer can then be compared again in seconds.)
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from skyscatter import api
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.render.scene import diffuse_radiance, ground_viewpoint, sun_direction
from skyscatter.transport.cloud_monte_carlo import CloudMonteCarlo
from skyscatter.transport.clouds import cloud_transmittance

WAVELENGTHS_NM = [450.0, 550.0, 650.0]
SUN_ZENITH_DEG, SUN_AZIMUTH_DEG = 40.0, 135.0


def single_cumulus():
    """The cumulus preset thinned to 6 % cover: isolated clouds."""
    clouds = api.load_clouds("cumulus")
    layer = dataclasses.replace(clouds.layers[0], coverage=0.06,
                                shape=dataclasses.replace(clouds.layers[0].shape,
                                                          coverage_variation=0.0))
    return dataclasses.replace(clouds, layers=(layer,))


def aimed_at_a_cloud(field, origin: np.ndarray, size: int):
    """A perspective camera, 30 deg wide, centred on the direction above 35 deg elevation
    whose line of sight holds the most water (a cloud in the middle of the frame)."""
    scan = api.FisheyeCamera(96)
    directions, valid = scan.directions()
    rays = directions[valid & (directions[..., 2] > np.sin(np.radians(35.0)))]
    through = cloud_transmittance(field, origin, rays)[:, 0]
    best = rays[np.argmin(through)]
    heading = np.degrees(np.arctan2(best[0], best[1]))
    pitch = np.degrees(np.arcsin(best[2]))
    return api.PerspectiveCamera(size, size, 30.0, heading_deg=heading, pitch_deg=pitch)


def cases(size: int):
    """(name, clouds, observer altitude [m], camera or None for a fisheye)."""
    return [
        ("single cumulus, from the ground", single_cumulus(), 2.0, "aim"),
        ("cumulus field, from the ground", api.load_clouds("cumulus"), 2.0,
         api.FisheyeCamera(size)),
        ("stratus deck, from the ground", api.load_clouds("stratus"), 2.0,
         api.FisheyeCamera(size)),
        ("cumulus field, from 6 km", api.load_clouds("cumulus"), 6000.0,
         api.PerspectiveCamera(size, size, 60.0, heading_deg=135.0, pitch_deg=-45.0)),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paths", type=int, default=2000, help="Monte Carlo paths per pixel")
    parser.add_argument("--size", type=int, default=32, help="image side [pixels]")
    parser.add_argument("--figure", default=None, help="write the comparison figure here")
    parser.add_argument("--cases", default=None, help="comma-separated case numbers (from 0)")
    parser.add_argument("--renders", type=int, default=8,
                        help="renderer passes averaged (each with its own jitter)")
    parser.add_argument("--reference-cache", default=None,
                        help="folder keeping the Monte Carlo images for reuse")
    args = parser.parse_args()
    chosen = None if args.cases is None else {int(i) for i in args.cases.split(",")}
    atmosphere = api.load_atmosphere("earth")
    solver = api.load_solver(atmosphere, WAVELENGTHS_NM)
    profile = solver.profile
    sun_local = sun_direction(SUN_ZENITH_DEG, SUN_AZIMUTH_DEG)
    rows = []
    for number, (name, clouds, altitude, camera) in enumerate(cases(args.size)):
        if chosen is not None and number not in chosen:
            continue
        viewpoint = ground_viewpoint(altitude, profile.bottom_radius_m)
        field = cloud_field(clouds, profile.bottom_radius_m, profile.wavelengths_nm)
        if camera == "aim":
            camera = aimed_at_a_cloud(field, viewpoint.position_m, args.size)
        directions, valid = camera.directions()
        rays = viewpoint.direction_to_world(directions[valid])
        sun = viewpoint.direction_to_world(sun_local)
        start = time.perf_counter()
        ours, ours_error = renderer_mean(args.renders, rays.shape[0], lambda order, v=viewpoint,
                                         r=rays, s=sun, f=field: diffuse_radiance(
            solver, v.position_m, np.ascontiguousarray(r[order]), s, clouds=f))
        ours_s = (time.perf_counter() - start) / args.renders
        start = time.perf_counter()
        reference, error = monte_carlo(args, number, (profile, field, viewpoint, rays, sun))
        reference_s = time.perf_counter() - start
        print(f"{name}: {rays.shape[0]} pixels, renderer {ours_s:.1f} s, Monte Carlo "
              f"{reference_s:.0f} s ({args.paths} paths per pixel)")
        relative = ours / reference - 1.0
        noise = error / reference
        for k, wavelength in enumerate(profile.wavelengths_nm):
            mean_ours, mean_reference = ours[:, k].mean(), reference[:, k].mean()
            mean_noise = np.sqrt(np.sum(error[:, k] ** 2)) / rays.shape[0] / mean_reference
            print(f"  {wavelength:.0f} nm: image mean {mean_ours:.4g} vs {mean_reference:.4g} "
                  f"({mean_ours / mean_reference - 1:+.1%}, renderer noise "
                  f"{ours_error[k] / mean_ours:.2%}, reference noise {mean_noise:.2%}); "
                  f"per pixel median |e| {np.median(np.abs(relative[:, k])):.1%}, 90th "
                  f"percentile {np.percentile(np.abs(relative[:, k]), 90):.1%}; reference "
                  f"median relative standard error {np.median(noise[:, k]):.1%}")
        print_breakdown(cloud_transmittance(field, viewpoint.position_m, rays)[:, 1],
                        ours[:, 1], reference[:, 1])
        rows.append((name, directions.shape[:2], valid, ours[:, 1], reference[:, 1]))
    if args.figure:
        write_figure(rows, args.figure)


TRANSMITTANCE_CLASSES = (("clear sky (T > 0.9)", 0.9, 1.01),
                         ("thin edges (1e-3 < T < 0.3)", 1e-3, 0.3),
                         ("cloud bodies (T < 1e-3)", -1.0, 1e-3))


def print_breakdown(transmittance: np.ndarray, ours: np.ndarray, reference: np.ndarray) -> None:
    """At 550 nm, per class of the clouds' transmittance along the pixels: their share of the
    reference's light and the renderer's total over them against the reference's."""
    for label, low, high in TRANSMITTANCE_CLASSES:
        chosen = (transmittance > low) & (transmittance <= high)
        if chosen.any():
            share = reference[chosen].sum() / reference.sum()
            print(f"    {label}: {chosen.sum()} pixels, {share:.0%} of the light, renderer "
                  f"{ours[chosen].sum() / reference[chosen].sum() - 1:+.1%} (median "
                  f"{np.median(ours[chosen] / reference[chosen] - 1):+.1%})")


def renderer_mean(passes: int, n: int, render) -> tuple[np.ndarray, np.ndarray]:
    """The renderer's expected image (n, n_wl) of n rays and the standard error of its image
    mean (n_wl,): each ray's jitter follows from its index among the rays rendered
    (`_cloud_kernels`), so `render(order)` of the rays in `passes` shuffled orders gives
    independent passes."""
    generator = np.random.default_rng(19)
    images = []
    for number in range(passes):
        order = generator.permutation(n) if number else np.arange(n)
        image = np.empty_like(values := render(order))
        image[order] = values
        images.append(image)
    images = np.stack(images)
    means = images.mean(axis=1)  # (passes, n_wl)
    spread = means.std(axis=0, ddof=1) / np.sqrt(passes) if passes > 1 else np.zeros(
        means.shape[1])
    return images.mean(axis=0), spread


def monte_carlo(args, number: int, scene) -> tuple[np.ndarray, np.ndarray]:
    """The reference radiance and its standard error, from the cache folder when it holds
    this case at this size and number of paths."""
    profile, field, viewpoint, rays, sun = scene
    cached = None
    if args.reference_cache:
        folder = Path(args.reference_cache)
        folder.mkdir(parents=True, exist_ok=True)
        cached = folder / f"case{number}_size{args.size}_paths{args.paths}.npz"
        if cached.exists():
            with np.load(cached) as saved:
                if saved["rays"].shape == rays.shape and np.allclose(saved["rays"], rays):
                    return saved["reference"], saved["error"]
    reference, error = CloudMonteCarlo(profile, field, n_samples=args.paths).\
        radiance_with_error(viewpoint.position_m, rays, sun)
    if cached is not None:
        partial = cached.with_suffix(".partial.npz")
        np.savez(partial, rays=rays, reference=reference, error=error)
        partial.replace(cached)
    return reference, error


def write_figure(rows, path: str) -> None:
    """Renderer, Monte Carlo and their relative difference at 550 nm, one row per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(len(rows), 3, figsize=(9.0, 3.0 * len(rows)), squeeze=False)
    for row, (name, shape, valid, ours, reference) in zip(axes, rows, strict=True):
        images = []
        for values in (ours, reference, ours / reference - 1.0):
            image = np.full(shape, np.nan)
            image[valid] = values
            images.append(image)
        top = np.nanpercentile(images[1], 99)
        for axis, image, title in zip(row, images, ("renderer", "Monte Carlo",
                                                    "renderer / MC - 1"), strict=True):
            if title.startswith("renderer /"):
                shown = axis.imshow(image, cmap="RdBu_r", vmin=-0.5, vmax=0.5)
                figure.colorbar(shown, ax=axis, fraction=0.046)
            else:
                axis.imshow(image, cmap="gray", vmin=0.0, vmax=top)
            axis.set_title(f"{name}\n{title}" if title == "renderer" else title, fontsize=8)
            axis.set_xticks([])
            axis.set_yticks([])
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
