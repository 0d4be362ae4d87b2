"""Accuracy: the Monte Carlo reference in optically thick, forward-peaked layers, against DISORT,
for two source trees in one run (issue 17).

Cases (one band, 550 nm, sun 30 deg from the zenith, views 135 deg in azimuth from the sun's
unless stated), each on three of DISORT's quadrature directions (64 streams, 512 moments,
delta-M with the Nakajima-Tanaka corrections; `validate.disort.disort_sky_radiance`):
- a 1 km slab of the `earth-overcast` preset's water droplets (Mie, effective radius 10 um,
  forward peak 592 sr^-1) of optical depth 8 and 20 over a black ground, seen from below, and
  the 20 from above (`validate.slab.slab_profile` with the droplets' phase function);
- `earth-overcast` itself (a stratus of optical depth 20 between 600 and 1100 m under air,
  ozone and aerosol) from the ground looking up and from 3000 m looking down and up (the
  observer a boundary of DISORT's layers).
DISORT is computed here, once, with this tree's code; each tree's `MonteCarloSolver` runs in
its own process (`PYTHONPATH=TREE/src`) with `sun_sampling_probability=0` (what `skyscatter
validate` used for thick layers before the default became 0 there) and `--paths` paths per
direction. Printed: for each case and view, DISORT's radiance and each tree's Monte Carlo as a
ratio to it with its relative standard error and z = (MC - DISORT) / standard error, and each
tree's time per case.

Run: python benchmarks/compare_monte_carlo_thick.py --trees BEFORE_TREE AFTER_TREE
     [--paths 20000] [--seed 1]
e.g. `git worktree add /tmp/base 4f2f0a5` (before the thick-layer changes) and
`--trees /tmp/base .`. About 10 min per tree on 2 cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pickle
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.validate.disort import disort_sky_radiance, plane_parallel_layers
from skyscatter.validate.slab import SLAB_THICKNESS_M, slab_profile

SUN_ZENITH_DEG = 30.0
AZIMUTH_DEG = 135.0
UP_DEG = (10.0, 40.0, 70.0)
DOWN_DEG = (110.0, 140.0, 170.0)

CHILD = """
import pickle, sys, time
from pathlib import Path
from skyscatter.transport.monte_carlo import MonteCarloSolver
cases = pickle.loads(Path(sys.argv[1]).read_bytes())
paths, seed, out = int(sys.argv[2]), int(sys.argv[3]), Path(sys.argv[4])
results = []
for name, profile, position, views, sun in cases:
    start = time.perf_counter()
    mean, error = MonteCarloSolver(profile, n_samples=paths, seed=seed,
                                   sun_sampling_probability=0.0).sky_radiance_with_error(
        position, views, sun)
    results.append((mean[:, 0], error[:, 0], time.perf_counter() - start))
out.write_bytes(pickle.dumps(results))
"""


def droplet_slab(optical_depth: float):
    """`slab_profile` with the `earth-overcast` preset's cloud droplets as its phase function."""
    overcast = load_atmosphere("earth-overcast").optical_profile(np.array([550.0]))
    droplets = overcast.phases[overcast.names.index("cloud")]
    return dataclasses.replace(slab_profile(optical_depth), phases=(droplets,))


def case(name: str, profile, altitude_m: float, zeniths_deg: tuple[float, ...]):
    """(name, profile, observer position, views (3, 3), sun, DISORT radiance (3,)) on the
    DISORT directions nearest `zeniths_deg`."""
    layers = plane_parallel_layers(profile, n_moments=512, boundaries_m=(altitude_m,))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zenith, radiance = disort_sky_radiance(
            profile, np.radians(SUN_ZENITH_DEG), np.radians(AZIMUTH_DEG), np.pi, n_streams=64,
            layers=layers, altitude_m=altitude_m)
    chosen = [int(np.argmin(np.abs(np.degrees(zenith) - z))) for z in zeniths_deg]
    views = local_frame_directions(zenith[chosen], np.radians(AZIMUTH_DEG))
    sun = local_frame_directions(np.radians(SUN_ZENITH_DEG), 0.0)
    position = np.array([0.0, 0.0, profile.bottom_radius_m + altitude_m])
    return name, profile, position, views, sun, radiance[chosen, 0, 0]


def cases():
    overcast = load_atmosphere("earth-overcast").optical_profile(np.array([550.0]))
    top = SLAB_THICKNESS_M - 0.01  # just inside the slab's top
    return [case("droplet slab, optical depth 8, from below", droplet_slab(8.0), 0.0, UP_DEG),
            case("droplet slab, optical depth 20, from below", droplet_slab(20.0), 0.0, UP_DEG),
            case("droplet slab, optical depth 20, from above", droplet_slab(20.0), top,
                 DOWN_DEG),
            case("earth-overcast, ground, looking up", overcast, 0.0, UP_DEG),
            case("earth-overcast, 3000 m, looking down", overcast, 3000.0, DOWN_DEG),
            case("earth-overcast, 3000 m, looking up", overcast, 3000.0, UP_DEG)]


def run_tree(tree: Path, chosen, paths: int, seed: int):
    """Each case's (mean, standard error, seconds) from `tree`'s Monte Carlo."""
    with tempfile.TemporaryDirectory() as folder:
        cases_file, out = Path(folder, "cases.pkl"), Path(folder, "out.pkl")
        cases_file.write_bytes(pickle.dumps([c[:5] for c in chosen]))
        env = dict(os.environ, PYTHONPATH=str(tree / "src"))
        subprocess.run([sys.executable, "-c", CHILD, str(cases_file), str(paths), str(seed),
                        str(out)], env=env, check=True)
        return pickle.loads(out.read_bytes())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trees", type=Path, nargs="+", required=True)
    parser.add_argument("--paths", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    chosen = cases()
    results = {tree: run_tree(tree, chosen, args.paths, args.seed) for tree in args.trees}
    heads = " | ".join(f"{tree}: MC / DISORT (rel. error, z)" for tree in args.trees)
    print(f"\n| case | view zenith | DISORT | {heads} |")
    print("|---|---|---|" + "---|" * len(args.trees))
    for k, (name, _, _, views, _, disort) in enumerate(chosen):
        for j in range(3):
            cells = []
            for tree in args.trees:
                mean, error, _ = results[tree][k]
                cells.append(f"{mean[j] / disort[j]:.3f} ({100 * error[j] / mean[j]:.1f} %, "
                             f"{(mean[j] - disort[j]) / error[j]:+.1f})")
            zenith = np.degrees(np.arccos(np.clip(views[j, 2], -1.0, 1.0)))
            print(f"| {name} | {zenith:.1f}° | {disort[j]:.4f} | {' | '.join(cells)} |")
    for tree in args.trees:
        seconds = ", ".join(f"{r[2]:.0f}" for r in results[tree])
        print(f"{tree}: seconds per case {seconds} ({args.paths} paths per direction)")


if __name__ == "__main__":
    main()
