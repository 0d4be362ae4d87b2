"""The files of `skyscatter compare` (`validate.technique_comparison`): report.md (the tables
and figures) and results.json (every number, the raw radiances included, so that any figure of
the report can be recomputed), both written through a temporary file and a rename.

results.json: `plan` (solvers, atmospheres, sun zeniths, paths, frame), `wavelengths_nm`,
`view_zenith_deg` and `azimuth_deg` of the grid (azimuth from the sun's), `references` (per
atmosphere and sun zenith: the Monte Carlo `mean` and `standard_error` [W m^-2 sr^-1 nm^-1],
(n_directions, n_wl)), `cases` (per solver, atmosphere and sun zenith: `domain` (null, or the
solver's refusal) or `radiance` (n_directions, n_wl) with the medians and 95th percentiles of
|L / L_MC - 1| per band, of the luminance and of the (x, y) distance), `costs` (per solver and
atmosphere: precompute and frame times [s], peak traced memory [MiB]) and `capabilities`.
NaN is written as null.

Public names: `write_comparison_report`.
"""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path

import numpy as np

from skyscatter.validate.report import Figure, Table, atomic_write_text, format_percent

__all__ = ["write_comparison_report"]

NOT_IN_DOMAIN = "n/a (domain)"


def _plain(value):
    """numpy values as JSON: lists, floats, NaN and infinities as None."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, float | np.floating):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, np.integer | np.bool_):
        return value.item()
    return value


def _percentiles(values: np.ndarray) -> tuple[float, float]:
    """(median, 95th percentile) of the finite values; NaN for none."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return float("nan"), float("nan")
    return float(np.median(finite)), float(np.percentile(finite, 95.0))


def _case_json(case) -> dict:
    entry = {"solver": case.solver, "atmosphere": case.atmosphere,
             "sun_zenith_deg": case.sun_zenith_deg, "domain": case.domain}
    c = case.comparison
    if c is None:
        return entry
    lum, chroma = _percentiles(case.luminance_error), _percentiles(case.chromaticity_error)
    entry.update({
        "radiance": c.tables,
        "median_abs_relative_error": c.percentile(50.0),
        "p95_abs_relative_error": c.percentile(95.0),
        "luminance_median_abs_relative_error": lum[0],
        "luminance_p95_abs_relative_error": lum[1],
        "chromaticity_median_xy_distance": chroma[0],
        "chromaticity_p95_xy_distance": chroma[1],
        "share_within_two_standard_errors": c.within_noise,
    })
    return entry


def _results_json(result) -> dict:
    plan = result.plan
    references, seen = [], set()
    for case in result.cases:
        c = case.comparison
        if c is None or (case.atmosphere, case.sun_zenith_deg) in seen:
            continue
        seen.add((case.atmosphere, case.sun_zenith_deg))
        references.append({"atmosphere": case.atmosphere, "sun_zenith_deg": c.sun_zenith_deg,
                           "paths_per_direction_and_band": c.paths,
                           "mean": c.monte_carlo, "standard_error": c.standard_error,
                           "median_relative_standard_error": c.noise})
    costs = [{"solver": k.solver, "atmosphere": k.atmosphere, "domain": k.domain,
              "precompute_wall_s": k.precompute_wall_s, "precompute_cpu_s": k.precompute_cpu_s,
              "tables_from_cache": k.tables_cached, "frame_1920x1080_wall_s": k.frame_wall_s,
              "frame_1920x1080_cpu_s": k.frame_cpu_s, "peak_traced_mib": k.peak_traced_mib}
             for k in result.costs]
    return _plain({
        "plan": {"solvers": plan.solvers, "atmospheres": plan.atmospheres,
                 "sun_zeniths_deg": plan.sun_zeniths_deg, "quick": plan.quick,
                 "day_paths": plan.day_paths, "twilight_paths": plan.twilight_paths,
                 "target_relative_error": plan.target_relative_error,
                 "frame_size": plan.frame_size, "frame_scale": plan.frame_scale,
                 "frame_sun_zenith_deg": plan.frame_sun_zenith_deg,
                 "fresh_tables": plan.fresh_tables},
        "wavelengths_nm": result.wavelengths_nm,
        "view_zenith_deg": plan.grid.view_zenith_deg, "azimuth_deg": plan.grid.azimuth_deg,
        "references": references,
        "cases": [_case_json(case) for case in result.cases],
        "costs": costs,
        "capabilities": result.capabilities,
        "monte_carlo_seconds": result.reference_seconds,
        "monte_carlo_cases_from_cache": result.reference_cached,
    })


def _pair(median: float, p95: float, digits: int = 1) -> str:
    if not np.isfinite(median):
        return "–"
    return f"{format_percent(median, digits)} / {format_percent(p95, digits)}"


def _case_rows(result, atmosphere: str, n_cells: int, cells) -> list[list[str]]:
    """A row per case of `atmosphere`: solver, sun zenith, then `cells(case)` (n_cells), or
    NOT_IN_DOMAIN in each where the solver refused the case."""
    return [[case.solver, f"{case.sun_zenith_deg:g}",
             *([NOT_IN_DOMAIN] * n_cells if case.comparison is None else cells(case))]
            for case in result.cases if case.atmosphere == atmosphere]


def _summary_cells(case) -> list[str]:
    c = case.comparison
    worst = [float(np.nanmax(v)) if np.any(np.isfinite(v)) else float("nan")
             for v in (c.percentile(50.0), c.percentile(95.0))]
    chroma = _percentiles(case.chromaticity_error)
    return [_pair(*worst), _pair(*_percentiles(case.luminance_error)),
            f"{chroma[0]:.4f} / {chroma[1]:.4f}", format_percent(float(np.nanmax(c.noise)), 1)]


def _summary_table(result, atmosphere: str) -> Table:
    rows = _case_rows(result, atmosphere, 4, _summary_cells)
    return Table(f"{atmosphere}: median / 95th percentile over the view grid of the relative "
                 "error against the Monte Carlo reference, L / L_MC - 1 (radiance, the worst "
                 "band's) and Y / Y_MC - 1 (luminance), in absolute value, and of the distance "
                 "of the CIE 1931 chromaticity (x, y) from the reference's",
                 ["solver", "sun zenith [deg]", "radiance, worst band", "luminance",
                  "chromaticity Δxy", "MC noise, worst band"], rows)


def _band_table(result, atmosphere: str) -> Table:
    rows = _case_rows(result, atmosphere, result.wavelengths_nm.size, lambda case: [
        _pair(m, p) for m, p in zip(case.comparison.percentile(50.0),
                                    case.comparison.percentile(95.0), strict=True)])
    return Table(f"{atmosphere}: median / 95th percentile of |L / L_MC - 1| per band",
                 ["solver", "sun zenith [deg]"]
                 + [f"{w:.0f} nm" for w in result.wavelengths_nm], rows)


def _seconds(value: float | None) -> str:
    return "–" if value is None else f"{value:.2f} s"


def _cost_table(result) -> Table:
    plan = result.plan
    frame = (f"{plan.frame_size[0]} x {plan.frame_size[1]}" if plan.frame_scale == 1.0 else
             f"{plan.frame_size[0]} x {plan.frame_size[1]} x {plan.frame_scale:g}")
    rows = []
    for k in result.costs:
        if k.domain is not None:
            rows.append([k.solver, k.atmosphere] + [NOT_IN_DOMAIN] * 3)
            continue
        pre = f"{_seconds(k.precompute_cpu_s)} ({_seconds(k.precompute_wall_s)})"
        if k.tables_cached:
            pre += ", tables from the cache"
        rows.append([k.solver, k.atmosphere, pre,
                     f"{_seconds(k.frame_cpu_s)} ({_seconds(k.frame_wall_s)})",
                     f"{k.peak_traced_mib:.0f}"])
    return Table(f"Cost: CPU (wall) time to build each solver and answer its first ray, and of "
                 f"a 1920 x 1080 panorama ({frame} pixels timed, sun zenith "
                 f"{plan.frame_sun_zenith_deg:g} deg, {result.wavelengths_nm.size} bands), peak "
                 "memory traced by tracemalloc over both (numpy arrays; numba's own not traced)."
                 " The first run on a machine also compiles the kernels: time a second run",
                 ["solver", "atmosphere", "precompute CPU (wall)", "frame CPU (wall)",
                  "peak traced [MiB]"], rows)


def _capability_table(result) -> Table:
    names = list(result.capabilities)
    if not names:
        return Table("What each solver can do", ["solver"], [])
    columns = list(result.capabilities[names[0]])
    rows = [[n] + ["yes" if result.capabilities[n][c] else "no" for c in columns]
            for n in names]
    return Table("What each solver can do (its `SolverDomain` and capability protocols, "
                 "transport/solvers.py)", ["solver"] + columns, rows)


def _markdown(result, figures: list[Figure]) -> str:
    plan = result.plan
    grid = plan.grid
    zeniths = ", ".join(f"{z:g}" for z in np.unique(grid.view_zenith_deg))
    azimuths = ", ".join(f"{a:g}" for a in np.unique(grid.azimuth_deg))
    lines = [
        "# skyscatter technique comparison", "",
        f"{'Quick' if plan.quick else 'Standard'} run on {os.cpu_count()} cores "
        f"({platform.processor() or platform.machine()}). Sky radiance seen from the ground "
        f"on {grid.view_zenith_deg.size} directions (view zenith {zeniths} deg x azimuth from "
        f"the sun {azimuths} deg) at {result.wavelengths_nm.size} bands "
        f"({result.wavelengths_nm[0]:.1f}-{result.wavelengths_nm[-1]:.1f} nm), against the "
        f"Monte Carlo reference ({plan.day_paths} paths per direction and band with the sun "
        f"up, {plan.twilight_paths} below the horizon"
        + (f"; in forward-peaked media by day paths added up to a relative standard error of "
           f"{100 * plan.target_relative_error:g} %" if plan.target_relative_error else "")
        + f"; {result.reference_seconds:.0f} s of Monte Carlo in this run, "
        f"{result.reference_cached} cases from the cache). Errors are |L / L_MC - 1| over "
        "the grid; the Monte Carlo noise (median relative standard error) is beside them: "
        "errors near it measure the reference, not the solver. A solver outside its domain "
        f"for a case shows {NOT_IN_DOMAIN}.", ""]
    for atmosphere in plan.atmospheres:
        lines += [_summary_table(result, atmosphere).markdown(), ""]
    lines += [_cost_table(result).markdown(), "", _capability_table(result).markdown(), ""]
    for figure in figures:
        lines += [f"![{figure.caption}]({figure.path})", "", f"*{figure.caption}*", ""]
    lines += ["## Per band", ""]
    for atmosphere in plan.atmospheres:
        lines += [_band_table(result, atmosphere).markdown(), ""]
    refusals = sorted({(c.solver, c.domain) for c in result.cases if c.domain})
    if refusals:
        lines += ["## Outside the domain", ""]
        lines += [f"- {solver}: {reason}" for solver, reason in refusals] + [""]
    return "\n".join(lines)


def write_comparison_report(result, figures: list[Figure], output_dir: Path) -> list[Path]:
    """Write report.md and results.json into `output_dir`; return every file of the run (the
    figures included)."""
    out = Path(output_dir)
    report, results = out / "report.md", out / "results.json"
    atomic_write_text(report, _markdown(result, figures))
    atomic_write_text(results, json.dumps(_results_json(result), indent=1,
                                          allow_nan=False) + "\n")
    return [report, results] + [out / f.path for f in figures]
