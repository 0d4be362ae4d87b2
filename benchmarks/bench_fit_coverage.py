"""Synthetic retrievals: does `fit` recover the truth within its stated uncertainty?

One Monte Carlo computation of an AERONET-like almucantar (sun zenith 60 deg, view zenith
60 deg, 9 azimuths 6-180 deg from the sun, 440/675/870 nm) of the `earth` preset at a known
aerosol optical depth (tau(500 nm) = 0.15) plus its direct-sun transmittance; then N_TRIALS
noise realisations (radiance 3 % relative, the order of AERONET's sky-channel calibration
uncertainty, Holben et al. 1998, Remote Sens. Environ. 66, 1, doi:10.1016/S0034-4257(98)00031-5;
transmittance 0.01 absolute), each fitted for tau with a fast forward model and its stated
model error. Counts the trials whose truth lies within 1 and 2 stated sigma (68 % and 95 % for
correct, Gaussian uncertainties) and prints the retrieval error and the time per fit.

Forward models: interpolation in a sweep of 8 optical depths made by "hillaire" and by "lut"
(`api.sweep`), with and without the transmittance rows; the "hillaire" solver
itself for a few trials (time per fit); one fit with hillaire refined with the tables and
checked by the Monte Carlo (time of each stage).

    PYTHONPATH=src python benchmarks/bench_fit_coverage.py [N_TRIALS] [MC_PATHS]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from skyscatter import api
from skyscatter.atmosphere.config_overrides import atmosphere_with, load_document
from skyscatter.sweep.plan import dimension_name

KEY = "constituent[2].optics.optical_depth"
TRUTH = 0.15
SUN, VIEW = 60.0, 60.0
AZIMUTHS = [6.0, 10.0, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0, 180.0]
WAVELENGTHS = [440.0, 675.0, 870.0]
GRID = [0.02, 0.05, 0.08, 0.12, 0.18, 0.27, 0.4, 0.6]
NOISE = 0.03
TRANSMITTANCE_NOISE = 0.01


def truth_rows(paths: int) -> list[dict]:
    """Monte Carlo radiances and ray-marched transmittances at the truth."""
    document, path = load_document("earth")
    atmosphere = atmosphere_with(document, path, {KEY: TRUTH})
    sky = api.sky_radiance_rows(atmosphere, [SUN], [VIEW], AZIMUTHS, WAVELENGTHS,
                                solver="montecarlo",
                                options=api.solver_options(atmosphere, n_samples=paths))
    sun = api.irradiance_rows(atmosphere, [SUN], WAVELENGTHS, solver="single",
                              transmittance=True)
    return sky, sun


def trial_rows(sky: list[dict], sun: list[dict], rng: np.random.Generator) -> list[dict]:
    """One noisy measurement set: the Monte Carlo's own noise stays in, and counts in the
    stated uncertainty beside the added 3 %."""
    rows = []
    for r in sky:
        value = r["radiance"] * (1.0 + NOISE * rng.standard_normal())
        sigma = float(np.hypot(NOISE * r["radiance"], r["standard_error"]))
        rows.append({k: r[k] for k in ("sun_zenith_deg", "view_zenith_deg",
                                       "relative_azimuth_deg", "wavelength_nm")}
                    | {"radiance": value, "uncertainty": sigma})
    for r in sun:
        value = r["direct_transmittance"] + TRANSMITTANCE_NOISE * rng.standard_normal()
        rows.append({"sun_zenith_deg": r["sun_zenith_deg"], "wavelength_nm": r["wavelength_nm"],
                     "direct_transmittance": value, "uncertainty": TRANSMITTANCE_NOISE})
    return rows


def coverage(model, sky, sun, trials: int, **kwargs) -> dict:
    """Fits of `trials` noise realisations; coverage, bias, spread, time."""
    rng = np.random.default_rng(2026)
    estimates, sigmas, seconds = [], [], []
    for _ in range(trials):
        result = api.fit("earth", trial_rows(sky, sun, rng), [f"{KEY}=0.02:0.6:0.1"],
                         model=model, **kwargs)
        estimates.append(result.estimates[KEY])
        sigmas.append(result.uncertainties[KEY])
        seconds.append(result.report["seconds"])
    e, s = np.array(estimates), np.array(sigmas)
    z = np.abs(e - TRUTH) / s
    return {"within_1_sigma": float(np.mean(z <= 1.0)),
            "within_2_sigma": float(np.mean(z <= 2.0)), "mean_error": float(np.mean(e - TRUTH)),
            "rms_error": float(np.sqrt(np.mean((e - TRUTH) ** 2))),
            "median_sigma": float(np.median(s)), "seconds_per_fit": float(np.median(seconds))}


def main() -> None:
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 50
    paths = int(sys.argv[2]) if len(sys.argv) > 2 else 20_000
    start = time.perf_counter()
    sky, sun = truth_rows(paths)
    relative = np.median([r["standard_error"] / r["radiance"] for r in sky])
    print(f"Monte Carlo truth: {len(sky)} radiances, {paths} paths, median relative standard "
          f"error {100 * relative:.2f} %, {time.perf_counter() - start:.0f} s", flush=True)
    for solver in ("hillaire", "lut"):
        start = time.perf_counter()
        path = Path(f"/tmp/fit_sweep_{solver}.nc")
        api.sweep("earth", {KEY: GRID}, [SUN], [VIEW], AZIMUTHS, wavelengths_nm=WAVELENGTHS,
                  solver=solver, output_path=path, restart=True)
        built = time.perf_counter() - start
        print(f"sweep {solver} ({dimension_name(KEY)}: {len(GRID)} values) {built:.0f} s",
              flush=True)
        print(f"  {trials} trials, radiance + transmittance: {coverage(path, sky, sun, trials)}",
              flush=True)
        print(f"  {trials} trials, radiance only: {coverage(path, sky, [], trials)}", flush=True)
    print(f"solver hillaire, 5 trials: {coverage(None, sky, [], 5, solver='hillaire')}",
          flush=True)
    rows = trial_rows(sky, [], np.random.default_rng(5))
    result = api.fit("earth", rows, [f"{KEY}=0.02:0.6:0.1"], refine="lut",
                     checks=["montecarlo"], check_samples=paths)
    stages = [(s["model"], round(s["estimates"][KEY], 4), round(s["uncertainties"][KEY], 4),
               s["evaluations"], round(s["seconds"], 1)) for s in result.report["stages"]]
    check = result.report["checks"][0]
    print(f"hillaire -> lut -> montecarlo check (model, estimate, sigma, evaluations, s): "
          f"{stages}; check chi-square {check['chi_square_measurement_only']:.1f} for "
          f"{check['values']} values, lut vs Monte Carlo "
          f"{check['fitted_model_minus_check']}, {check['seconds']:.0f} s; total "
          f"{result.report['seconds']:.0f} s", flush=True)


if __name__ == "__main__":
    main()
