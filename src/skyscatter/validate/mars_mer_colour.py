"""The colour of the daytime Martian sky against the Mars Exploration Rovers' Pancam
(Meyran 2022 §5.1.2, the thesis's Figs. 5.6, 5.7 and 5.9).

Bell et al. (2006; the thesis's ref. [57], quoted by Meyran 2022) measured the CIE
1931 chromaticity of the sky with calibrated Pancam images through the L4/L5/L6 filters (482,
535, 601 nm): a horizon survey 3 deg above the horizon, due west, with the sun high, and sky
surveys at several times of day, for Spirit and Opportunity in their first year. The thesis
quotes the four datasets' means, x = 0.408, 0.396, 0.405, 0.400 and y = 0.382, 0.383, 0.377,
0.381 (mean 0.402, 0.381; it does not say which is which), and finds Collienne's model the
farthest (its mean x = 0.313, y = 0.318) and the hybrid the closest; a red sky "needs quite
dense dust" (Fig. 5.9).

Here: x, y of the spectral sky radiance (Monte Carlo, all orders) 3 deg above the horizon,
90 deg in azimuth from the sun (the horizon survey), for sun elevations 20-90 deg, averaged over
the sun elevations, for each model and for scaled dust amounts of the hybrid. The dust of each
is given as its vertical optical depth at 550 nm; the optical depth that fits best is
interpolated along the scan (piecewise linear in log tau). Collienne's preset is also computed
with its "inverted Rayleigh" coefficients read in the reverse wavelength order, the one its
framework config shares with Costa's (Meyran 2022 App. A.1.2), to test whether that reading
is what the thesis computed.

Public names: `KEY`, `MEASURED_X`, `MEASURED_Y`, `MEASURED_MEAN`, `ColourTrack`,
`best_fit_optical_depth`, `horizon_survey_xy`, `run`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.validate.mars_models import (
    MODEL_COLOURS,
    MODEL_LABELS,
    SCAN_MODEL,
    dust_optical_depth,
    dust_scaled,
    framework_reading,
    load_models,
    monte_carlo_solver,
    sky_chromaticity,
    sky_direction,
)
from skyscatter.validate.plots import new_figure, save_figure
from skyscatter.validate.report import CaseResult, Check, Figure, Table, ValidationSettings

__all__ = ["KEY", "MEASURED_MEAN", "MEASURED_X", "MEASURED_Y", "ColourTrack",
           "best_fit_optical_depth", "horizon_survey_xy", "run"]

KEY = "mars-mer-colour"
# Bell et al. 2006 via the thesis (Meyran 2022 §5.1.2): the four MER datasets' mean chromaticity
MEASURED_X = (0.408, 0.396, 0.405, 0.400)
MEASURED_Y = (0.382, 0.383, 0.377, 0.381)
MEASURED_MEAN = (float(np.mean(MEASURED_X)), float(np.mean(MEASURED_Y)))  # 0.402, 0.381
THESIS_COLLIENNE = (0.313, 0.318)  # the thesis's Collienne mean (Meyran 2022 §5.1.2)
VIEW_ELEVATION_DEG = 3.0  # the horizon survey: 3 deg above the horizon
VIEW_AZIMUTH_DEG = 90.0  # due west with the sun high: about 90 deg from the sun's azimuth
SUN_ELEVATIONS_DEG = (20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0)
QUICK_SUN_ELEVATIONS_DEG = (30.0, 60.0, 90.0)
BANDS, QUICK_BANDS = 16, 8
# Monte Carlo paths per direction and band: the standard error of x, y is ~0.001 per sun
# elevation at 10 000 (compared with the tables, which agree within 0.002 in this geometry)
PATHS, QUICK_PATHS = 10_000, 3_000
SCAN_FACTORS = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)  # times the scanned model's dust
QUICK_SCAN_FACTORS = (8.0,)
FIT_LIMIT = 0.02  # best model within 0.02 in x and y (the four datasets span 0.012 in x)
REPRODUCTION_LIMIT = 0.03  # Collienne's mean within 0.03 of the thesis's


@dataclass(frozen=True)
class ColourTrack:
    """A model's horizon-survey chromaticity over sun elevation."""

    label: str
    model: str
    dust_factor: float
    dust_optical_depth_550: float  # vertical [-]
    sun_elevation_deg: np.ndarray  # (n,)
    xy: np.ndarray  # (n, 2)

    @property
    def mean(self) -> np.ndarray:
        """x, y averaged over the sun elevations. [-]"""
        return self.xy.mean(axis=0)

    def offset(self, target: ArrayLike = MEASURED_MEAN) -> np.ndarray:
        """Mean x, y minus `target`. [-]"""
        return self.mean - np.asarray(target, dtype=np.float64)

    def distance(self, target: ArrayLike = MEASURED_MEAN) -> float:
        """max(|dx|, |dy|) of the mean from `target`. [-]"""
        return float(np.max(np.abs(self.offset(target))))


def horizon_survey_xy(solver, sun_elevations_deg: ArrayLike,
                      view_elevation_deg: float = VIEW_ELEVATION_DEG,
                      view_azimuth_deg: float = VIEW_AZIMUTH_DEG) -> np.ndarray:
    """CIE 1931 x, y (n, 2) of the sky `view_elevation_deg` [deg] above the horizon,
    `view_azimuth_deg` [deg] from the sun's azimuth, for each sun elevation [deg]."""
    view = sky_direction(view_elevation_deg, view_azimuth_deg)
    return np.array([sky_chromaticity(solver, view, sky_direction(float(e), 0.0))
                     for e in np.atleast_1d(sun_elevations_deg)])


def run(settings: ValidationSettings) -> CaseResult:
    """The MER-colour case of `skyscatter validate` (module docstring)."""
    start = time.perf_counter()
    models = load_models()
    quick = settings.quick
    grid = wavelength_grid(QUICK_BANDS if quick else BANDS)
    paths = QUICK_PATHS if quick else PATHS
    elevations = np.array(QUICK_SUN_ELEVATIONS_DEG if quick else SUN_ELEVATIONS_DEG)
    tracks: list[ColourTrack] = []
    for name in models.names:
        atmosphere = models.atmospheres[name]
        solver = monte_carlo_solver(atmosphere, grid, settings, paths)
        tracks.append(ColourTrack(MODEL_LABELS[name], name, 1.0,
                                  dust_optical_depth(atmosphere, 550.0), elevations,
                                  horizon_survey_xy(solver, elevations)))
    scan: list[ColourTrack] = []
    if SCAN_MODEL in models.atmospheres:
        for factor in QUICK_SCAN_FACTORS if quick else SCAN_FACTORS:
            same = [t for t in tracks if t.model == SCAN_MODEL and factor == 1.0]
            if same:
                scan.append(same[0])
                continue
            atmosphere = dust_scaled(models.atmospheres[SCAN_MODEL], factor)
            solver = monte_carlo_solver(atmosphere, grid, settings, paths)
            scan.append(ColourTrack(f"{MODEL_LABELS[SCAN_MODEL]}, dust x{factor:g}",
                                    SCAN_MODEL, factor, dust_optical_depth(atmosphere, 550.0),
                                    elevations, horizon_survey_xy(solver, elevations)))
    reading = None
    if "mars-collienne" in models.atmospheres:
        variant = framework_reading(models.atmospheres["mars-collienne"])
        if variant is not None:
            solver = monte_carlo_solver(variant, grid, settings, paths)
            reading = ColourTrack("Collienne, gas coefficients reversed", "mars-collienne", 1.0,
                                  dust_optical_depth(variant, 550.0), elevations,
                                  horizon_survey_xy(solver, elevations))
    candidates = tracks + [t for t in scan if not any(t is u for u in tracks)]
    best = min(candidates, key=lambda t: t.distance()) if candidates else None
    collienne = next((t for t in tracks if t.model == "mars-collienne"), None)

    fit = best_fit_optical_depth(scan) if len(scan) > 2 else None
    result = CaseResult(KEY, "Mars daytime sky colour vs MER Pancam",
                        _summary(tracks, scan, best, collienne, reading, elevations, fit))
    result.tables = [_table(candidates + ([reading] if reading else []))]
    result.metrics = {
        "measured_mean_xy": list(MEASURED_MEAN), "measured_x": list(MEASURED_X),
        "measured_y": list(MEASURED_Y), "bands": int(grid.size),
        "sun_elevations_deg": elevations.tolist(), "skipped": dict(models.missing),
        "tracks": {t.label: {"dust_factor": t.dust_factor,
                             "dust_optical_depth_550nm": t.dust_optical_depth_550,
                             "xy": t.xy.tolist(), "mean_xy": t.mean.tolist(),
                             "distance": t.distance()}
                   for t in candidates + ([reading] if reading else [])},
        "best": best.label if best else None,
        "best_fit_dust_optical_depth_550nm": fit[0] if fit else None,
        "best_fit_distance": fit[1] if fit else None,
        "solver": "montecarlo", "paths_per_direction_and_band": paths,
    }
    if best is not None:
        result.checks.append(Check(
            f"best model/dust ({best.label}): max(|dx|, |dy|) of its mean x, y from the MER "
            f"mean ({MEASURED_MEAN[0]:.3f}, {MEASURED_MEAN[1]:.3f})", best.distance(),
            FIT_LIMIT))
    if reading is not None:
        result.checks.append(Check(
            "Collienne with its gas coefficients in the framework's order: max(|dx|, |dy|) "
            f"from the thesis's Collienne mean ({THESIS_COLLIENNE[0]}, {THESIS_COLLIENNE[1]})",
            reading.distance(THESIS_COLLIENNE), REPRODUCTION_LIMIT))
    if candidates:
        result.figures = [_figure(tracks, scan, reading, settings)]
    result.notes = models.notes() + _notes(collienne, reading, quick)
    result.seconds = time.perf_counter() - start
    return result


def best_fit_optical_depth(scan: list[ColourTrack], target: ArrayLike = MEASURED_MEAN
                           ) -> tuple[float, float]:
    """The dust optical depth at 550 nm whose mean x, y comes closest to `target` (smallest
    max(|dx|, |dy|)), with mean x and y interpolated piecewise linearly in log(tau) between
    the scanned amounts, and that distance. [-]"""
    ordered = sorted(scan, key=lambda t: t.dust_optical_depth_550)
    log_tau = np.log([t.dust_optical_depth_550 for t in ordered])
    means = np.array([t.mean for t in ordered])
    fine = np.linspace(log_tau[0], log_tau[-1], 2001)
    x = np.interp(fine, log_tau, means[:, 0])
    y = np.interp(fine, log_tau, means[:, 1])
    target = np.asarray(target, dtype=np.float64)
    distance = np.maximum(np.abs(x - target[0]), np.abs(y - target[1]))
    i = int(np.argmin(distance))
    return float(np.exp(fine[i])), float(distance[i])


def _summary(tracks: list[ColourTrack], scan: list[ColourTrack], best: ColourTrack | None,
             collienne: ColourTrack | None, reading: ColourTrack | None,
             elevations: np.ndarray, fit: tuple[float, float] | None) -> str:
    means = "; ".join(f"{t.label} ({t.mean[0]:.3f}, {t.mean[1]:.3f})" for t in tracks)
    text = (
        f"CIE 1931 x, y of the sky {VIEW_ELEVATION_DEG:g} deg above the horizon, "
        f"{VIEW_AZIMUTH_DEG:g} deg in azimuth from the sun (Pancam's horizon survey), averaged "
        f"over sun elevations {elevations.min():g}-{elevations.max():g} deg, against the mean "
        f"of the four MER datasets of Bell et al. (2006) quoted by the thesis, "
        f"({MEASURED_MEAN[0]:.3f}, {MEASURED_MEAN[1]:.3f}). Model means: {means or 'none'}.")
    if scan:
        text += (f" Scaling the {MODEL_LABELS[SCAN_MODEL]}'s dust: " + "; ".join(
            f"x{t.dust_factor:g} (tau550 {t.dust_optical_depth_550:.2f}): ({t.mean[0]:.3f}, "
            f"{t.mean[1]:.3f})" for t in scan) + ".")
    if best is not None:
        dx, dy = best.offset()
        text += (f" Closest: {best.label} (dx {dx:+.3f}, dy {dy:+.3f}).")
    if fit is not None:
        text += (f" Interpolated along the scan, the best fit is a dust optical depth of "
                 f"{fit[0]:.2f} at 550 nm (max(|dx|, |dy|) {_small(fit[1])}); Lemmon et al. "
                 "(2004, Science 306, 1753, doi:10.1126/science.1104474) measured a visible "
                 "optical depth of 0.9 at both rover sites early in the mission, falling "
                 "during it.")
    if collienne is not None:
        dx, dy = collienne.offset(THESIS_COLLIENNE)
        text += (f" Collienne's preset gives ({collienne.mean[0]:.3f}, {collienne.mean[1]:.3f}), "
                 f"{dx:+.3f}/{dy:+.3f} from the thesis's (0.313, 0.318)")
        text += (f"; with its gas coefficients reversed ({reading.mean[0]:.3f}, "
                 f"{reading.mean[1]:.3f})." if reading is not None else ".")
    return text


def _small(value: float) -> str:
    return "< 0.001" if value < 0.0005 else f"= {value:.3f}"


def _table(tracks: list[ColourTrack]) -> Table:
    rows = []
    for t in tracks:
        dx, dy = t.offset()
        rows.append([t.label, f"{t.dust_optical_depth_550:.3f}", f"{t.mean[0]:.4f}",
                     f"{t.mean[1]:.4f}", f"{dx:+.4f}", f"{dy:+.4f}",
                     f"{t.xy[:, 0].min():.3f}-{t.xy[:, 0].max():.3f}",
                     f"{t.xy[:, 1].min():.3f}-{t.xy[:, 1].max():.3f}"])
    return Table(f"Horizon-survey chromaticity, mean over sun elevations, against the MER mean "
                 f"({MEASURED_MEAN[0]:.3f}, {MEASURED_MEAN[1]:.3f})",
                 ["model", "dust tau(550 nm)", "mean x", "mean y", "dx", "dy",
                  "x range (sun elev.)", "y range"], rows)


def _notes(collienne: ColourTrack | None, reading: ColourTrack | None,
           quick: bool) -> list[str]:
    notes = [
        "Bell et al.'s horizon survey looked due west around noon; 'sun high' is taken as "
        "20-90 deg and due west as 90 deg in azimuth from the sun. The thesis averages its "
        "models over 0-90 deg; below 20 deg the colour changes fastest (its Fig. 5.7), which "
        "is why it is left out here. The measured values' own spread (0.012 in x, 0.006 in y) "
        "is the scale of the 0.02 limit.",
        "The colour is that of the spectral radiance under the preset's sun (no white "
        "balance, as the thesis's configs: white_balance false).",
        "Monte Carlo radiance (all orders). In this geometry (3 deg up, 90 deg from a high "
        "sun) the precomputed tables agree with it within 0.002 in x and y (hybrid and Blue "
        "Moon's, sun 20-90 deg; measured once, not part of the case).",
    ]
    if collienne is not None and reading is not None:
        notes.append(
            "Collienne: the preset (inverted Rayleigh as Collienne et al. 2013 meant it, 5.75e-6 "
            "m^-1 at 440 nm rising to 19.9e-6 at 680 nm) gives a butterscotch sky far from the "
            "thesis's bluish-white (0.313, 0.318). Read in the reverse order, as the thesis's "
            "framework config lists the same numbers in Costa's (680, 550, 440) order, the sky "
            "comes out within the limit of the thesis's value, so the checked reproduction uses "
            "that reading. But the thesis's Fig. 5.7 description (the sky opposite a low sun "
            "blue, turning orange above 10 deg) fits the preset's order, not the reversed one: "
            "which order the thesis's average came from is not settled.")
    if quick:
        notes.append(f"Quick mode: {QUICK_BANDS} bands, {QUICK_PATHS} paths, sun elevations "
                     f"{', '.join(f'{e:g}' for e in QUICK_SUN_ELEVATIONS_DEG)} deg, the dust "
                     f"scan only at x{', x'.join(f'{f:g}' for f in QUICK_SCAN_FACTORS)} "
                     f"(standard: {BANDS} bands, {PATHS} paths, x"
                     f"{', x'.join(f'{f:g}' for f in SCAN_FACTORS)}).")
    return notes


def _figure(tracks: list[ColourTrack], scan: list[ColourTrack], reading: ColourTrack | None,
            settings: ValidationSettings) -> Figure:
    figure, axis = new_figure(1, 1, width_in=6.4, height_in=5.2)
    axis.plot(MEASURED_X, MEASURED_Y, "ks", ms=6, label="MER datasets (Bell et al. 2006)")
    axis.plot(*MEASURED_MEAN, "k*", ms=12, label="MER mean")
    axis.add_patch(_square(MEASURED_MEAN, FIT_LIMIT))
    axis.plot(*THESIS_COLLIENNE, "o", mfc="none", mec=MODEL_COLOURS["mars-collienne"], ms=8,
              label="thesis: Collienne mean")
    for t in tracks:
        axis.plot(t.xy[:, 0], t.xy[:, 1], "o-", ms=3, lw=1.4, color=MODEL_COLOURS.get(t.model),
                  label=f"{t.label} (tau550 {t.dust_optical_depth_550:.2f})")
    shades = np.linspace(0.35, 0.9, max(len(scan), 1))
    for t, shade in zip(scan, shades, strict=False):
        if t.dust_factor == 1.0:
            continue
        axis.plot(t.xy[:, 0], t.xy[:, 1], "^--", ms=3, lw=1.0, color=(shade, 0.2, 0.2),
                  label=f"{t.label} (tau550 {t.dust_optical_depth_550:.2f})")
    if reading is not None:
        axis.plot(reading.xy[:, 0], reading.xy[:, 1], "o:", ms=3,
                  color=MODEL_COLOURS["mars-collienne"],
                  label=reading.label)
    axis.set_xlabel("CIE 1931 x")
    axis.set_ylabel("CIE 1931 y")
    axis.set_title("Horizon survey (3 deg up, 90 deg from the sun), sun 20-90 deg; box: "
                   f"+-{FIT_LIMIT} around the MER mean", fontsize=8)
    axis.set_aspect("equal", adjustable="datalim")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=6.5, loc="upper left")
    name = save_figure(figure, settings.output_dir, "mars_mer_colour.png")
    return Figure(name, "Sky chromaticity of each model over sun elevation (tracks) against "
                        "the four MER Pancam datasets: a redder sky needs more dust.")


def _square(centre: tuple[float, float], half_width: float):
    from matplotlib.patches import Rectangle

    return Rectangle((centre[0] - half_width, centre[1] - half_width), 2 * half_width,
                     2 * half_width, fill=False, ls="--", lw=0.8, color="0.4")
