"""Sky radiance along the sun's almucantar on Mars, as Meyran (2022) compares it with Mars
Pathfinder (its §5.1.1, Fig. 5.2).

Tomasko et al. (1999), J. Geophys. Res. 104(E4), 8987, doi:10.1029/98JE02658, measured the
sky radiance [W m^-2 sr^-1 nm^-1] with the Imager for Mars Pathfinder on sol 11 at 444, 671,
896 and 965 nm, the sun 12-29 deg high, at azimuths from the sun up to 180 deg. The thesis
evaluates its four models at 442.25 nm (its framework's grid, 360 + 11.75 i nm) with the sun 14 deg
high. The measured curves are not available here as numbers (only as a figure in the thesis),
so this case does not compare with them; it computes the four models' curves and checks the
thesis's published findings about their shapes (its §5.1.1 and conclusion):

- Blue Moon's (Mie dust) has the strongest forward peak: the largest L(5 deg) / L(90 deg);
- Collienne has "no forward peak": the smallest of the four;
- Blue Moon's has a back-scatter rise near 180 deg, L(180) / L(150) > 1,
- which the hybrid does not have: it converges to Costa's double Henyey-Greenstein there, so
  its L(180) / L(150) lies closer to Costa's than to Blue Moon's. (The ratio itself is > 1 for
  every model: the Rayleigh phase function of the gas alone gives (1 + 1) / (1 + cos^2 150) =
  1.14.)

Azimuths are measured from the sun along the almucantar at the sun's elevation; azimuth a is
the angular distance arccos(sin^2 e + cos^2 e cos a) from the sun (4.85 deg for a = 5 deg).
The radiance is the Monte Carlo solver's (all orders; the four checked azimuths with 10 times
the paths). In standard mode the case also reports the precomputed tables' radiance against it,
and Collienne's sky with its gas coefficients reversed (`mars_models.framework_reading`): the
thesis finds Collienne "the brightest" of the four, which only that reading reproduces away
from the sun (reported, not checked).

Public names: `KEY`, `AlmucantarCurve`, `almucantar_radiance`, `run`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import Atmosphere
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import NoisySolver, Solver
from skyscatter.validate.mars_models import (
    MODEL_COLOURS,
    MODEL_LABELS,
    angle_from_sun_deg,
    dust_optical_depth,
    framework_reading,
    load_models,
    mars_solver,
    monte_carlo_solver,
    sky_direction,
)
from skyscatter.validate.plots import new_figure, save_figure
from skyscatter.validate.report import CaseResult, Check, Figure, Table, ValidationSettings

__all__ = ["KEY", "AlmucantarCurve", "almucantar_radiance", "run"]

KEY = "mars-pathfinder"
WAVELENGTH_NM = 442.25  # the thesis's Fig. 5.2 (its framework's grid)
SUN_ELEVATION_DEG = 14.0  # the thesis's Fig. 5.2 (Tomasko's sol 11 sequences: 13-15 deg)
AZIMUTHS_DEG = tuple(2.5 * k for k in range(73))  # 0, 2.5, ..., 180
QUICK_AZIMUTHS_DEG = (0.0, 2.5, 5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0, 150.0, 165.0,
                      180.0)
FORWARD_DEG, SIDE_DEG = 5.0, 90.0  # forward peak: L(5) / L(90)
BACK_DEG, BEFORE_BACK_DEG = 180.0, 150.0  # back-scatter rise: L(180) / L(150)
CHECKED_DEG = (FORWARD_DEG, SIDE_DEG, BEFORE_BACK_DEG, BACK_DEG)
# Monte Carlo paths per direction: the curve, and the four checked azimuths. Measured standard
# errors (standard mode): 0.1-0.3 % near the sun, 0.6-0.8 % at 90-180 deg at 200 000 paths.
PATHS, CHECK_PATHS = 20_000, 200_000
QUICK_PATHS, QUICK_CHECK_PATHS = 4_000, 50_000
TABLE_ANGLES_DEG = (10.0, 20.0, 30.0, 90.0, 180.0)  # where the tables' error is reported
# The hybrid's L(180)/L(150) may go at most this fraction of the way from Costa's to Blue
# Moon's: closer to Costa's (it "converges to" Costa's phase function there, thesis §5.1.1).
HYBRID_BACK_FRACTION = 0.5
READING = "Collienne, gas coefficients reversed"


@dataclass(frozen=True)
class AlmucantarCurve:
    """One model's sky radiance along the sun's almucantar."""

    model: str
    azimuth_deg: np.ndarray  # (n,) from the sun, ascending
    radiance: np.ndarray  # (n,) [W m^-2 sr^-1 nm^-1]
    error: np.ndarray  # (n,) standard error of the radiance [W m^-2 sr^-1 nm^-1]
    dust_optical_depth: float  # vertical, at the wavelength [-]
    tables: np.ndarray | None = None  # (n,) the precomputed tables' radiance, if computed

    def at(self, azimuth_deg: float) -> float:
        """Radiance at `azimuth_deg` (linear interpolation). [W m^-2 sr^-1 nm^-1]"""
        return float(np.interp(azimuth_deg, self.azimuth_deg, self.radiance))

    def ratio(self, a_deg: float, b_deg: float) -> tuple[float, float]:
        """L(a) / L(b) at two sampled azimuths and its standard error. [-]"""
        i, j = (int(np.argmin(np.abs(self.azimuth_deg - v))) for v in (a_deg, b_deg))
        r = self.radiance[i] / self.radiance[j]
        rel = np.hypot(self.error[i] / self.radiance[i], self.error[j] / self.radiance[j])
        return float(r), float(r * rel)

    @property
    def forward_ratio(self) -> float:
        """L(5 deg) / L(90 deg): the forward peak. [-]"""
        return self.ratio(FORWARD_DEG, SIDE_DEG)[0]

    @property
    def back_ratio(self) -> float:
        """L(180 deg) / L(150 deg): > 1 is a rise towards the antisolar point. [-]"""
        return self.ratio(BACK_DEG, BEFORE_BACK_DEG)[0]


def almucantar_radiance(solver: Solver, azimuth_deg: ArrayLike,
                        sun_elevation_deg: float = SUN_ELEVATION_DEG
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Spectral sky radiance and its standard error, each (n, n_wl) [W m^-2 sr^-1 nm^-1], from
    the ground along the sun's almucantar (view elevation = `sun_elevation_deg` [deg]) at
    `azimuth_deg` [deg] from the sun. `solver` is any solver; the error is 0 unless it is a
    `NoisySolver` (Monte Carlo)."""
    azimuth = np.asarray(azimuth_deg, dtype=np.float64)
    views = sky_direction(np.full(azimuth.shape, sun_elevation_deg), azimuth)
    origin = observer_position(0.0, solver.profile.bottom_radius_m)
    sun = sky_direction(sun_elevation_deg, 0.0)
    if isinstance(solver, NoisySolver):
        return solver.sky_radiance_with_error(origin, views, sun)
    radiance = solver.sky_radiance(origin, views, sun)
    return radiance, np.zeros_like(radiance)


def _curve(name: str, atmosphere: Atmosphere, azimuths: np.ndarray,
           settings: ValidationSettings) -> AlmucantarCurve:
    """Monte Carlo radiance along the almucantar, more paths at the checked azimuths; in
    standard mode also the tables'."""
    quick = settings.quick
    checked = np.isin(azimuths, CHECKED_DEG)
    radiance, error = np.zeros(azimuths.size), np.zeros(azimuths.size)
    for mask, paths in ((~checked, QUICK_PATHS if quick else PATHS),
                        (checked, QUICK_CHECK_PATHS if quick else CHECK_PATHS)):
        solver = monte_carlo_solver(atmosphere, [WAVELENGTH_NM], settings, paths,
                                    monochromatic=True)
        mean, err = almucantar_radiance(solver, azimuths[mask])
        radiance[mask], error[mask] = mean[:, 0], err[:, 0]
    tables = None
    if not quick:
        solver = mars_solver(atmosphere, [WAVELENGTH_NM], settings, monochromatic=True)
        tables = almucantar_radiance(solver, azimuths)[0][:, 0]
    return AlmucantarCurve(name, azimuths, radiance, error,
                           dust_optical_depth(atmosphere, WAVELENGTH_NM), tables)


def run(settings: ValidationSettings) -> CaseResult:
    """The Pathfinder case of `skyscatter validate` (module docstring)."""
    start = time.perf_counter()
    models = load_models()
    azimuths = np.array(sorted(set(QUICK_AZIMUTHS_DEG if settings.quick else AZIMUTHS_DEG)
                               | set(CHECKED_DEG)))
    curves = {name: _curve(name, atmosphere, azimuths, settings)
              for name, atmosphere in models.atmospheres.items()}
    reading = None
    if not settings.quick and "mars-collienne" in models.atmospheres:
        variant = framework_reading(models.atmospheres["mars-collienne"])
        if variant is not None:
            solver = monte_carlo_solver(variant, [WAVELENGTH_NM], settings, PATHS,
                                        monochromatic=True)
            mean, err = almucantar_radiance(solver, azimuths)
            reading = AlmucantarCurve(READING, azimuths, mean[:, 0], err[:, 0],
                                      dust_optical_depth(variant, WAVELENGTH_NM))
    result = CaseResult(KEY, "Mars sky radiance along the almucantar (Pathfinder geometry)",
                        _summary(curves, reading))
    shown = curves | ({READING: reading} if reading else {})
    result.tables = [_table(shown)]
    if not settings.quick and curves:
        result.tables.append(_tables_table(curves))
    result.metrics = {
        "wavelength_nm": WAVELENGTH_NM, "sun_elevation_deg": SUN_ELEVATION_DEG,
        "solver": "montecarlo", "models": list(curves), "skipped": dict(models.missing),
        "azimuth_deg": azimuths.tolist(),
        "radiance": {n: c.radiance.tolist() for n, c in shown.items()},
        "standard_error": {n: c.error.tolist() for n, c in shown.items()},
        "forward_ratio_5_90": {n: c.ratio(FORWARD_DEG, SIDE_DEG) for n, c in shown.items()},
        "back_ratio_180_150": {n: c.ratio(BACK_DEG, BEFORE_BACK_DEG)
                               for n, c in shown.items()},
        "dust_optical_depth": {n: c.dust_optical_depth for n, c in curves.items()},
    }
    if not settings.quick:
        result.metrics["tables_radiance"] = {n: c.tables.tolist() for n, c in curves.items()}
    result.checks = _checks(curves)
    if curves:
        result.figures = [_figure(curves, reading, settings)]
    result.notes = models.notes() + _notes(curves, settings.quick)
    result.seconds = time.perf_counter() - start
    return result


def _label(name: str) -> str:
    return MODEL_LABELS.get(name, name)


def _brightest_away_from_the_sun(curves: dict[str, AlmucantarCurve]) -> str:
    """The model with the highest mean radiance at 30-180 deg from the sun."""
    def mean_far(c: AlmucantarCurve) -> float:
        return float(np.mean(c.radiance[c.azimuth_deg >= 30.0]))
    return _label(max(curves, key=lambda n: mean_far(curves[n])))


def _checks(curves: dict[str, AlmucantarCurve]) -> list[Check]:
    checks = []
    forward = {n: c.forward_ratio for n, c in curves.items()}
    if "mars-bluemoon" in curves and len(curves) > 1:
        others = [v for n, v in forward.items() if n != "mars-bluemoon"]
        checks.append(Check("Blue Moon's has the strongest forward peak: largest L(5)/L(90) of "
                            "the others / Blue Moon's", max(others) / forward["mars-bluemoon"],
                            1.0))
    if "mars-collienne" in curves and len(curves) > 1:
        others = [v for n, v in forward.items() if n != "mars-collienne"]
        checks.append(Check("Collienne has the weakest forward peak: its L(5)/L(90) / the "
                            "smallest of the others", forward["mars-collienne"] / min(others),
                            1.0))
    if "mars-bluemoon" in curves:
        r, e = curves["mars-bluemoon"].ratio(BACK_DEG, BEFORE_BACK_DEG)
        checks.append(Check(f"Blue Moon's rises towards 180 deg: L(150)/L(180) (< 1 is a rise; "
                            f"L(180)/L(150) = {r:.3f} +- {e:.3f})", 1.0 / r, 1.0))
    if all(n in curves for n in ("mars-costa", "mars-bluemoon", "mars-hybrid")):
        costa, moon, hybrid = (curves[n].back_ratio
                               for n in ("mars-costa", "mars-bluemoon", "mars-hybrid"))
        checks.append(Check("the hybrid's back scatter is Costa's, not Blue Moon's: its "
                            "L(180)/L(150) as a fraction of the way from Costa's to Blue Moon's",
                            (hybrid - costa) / (moon - costa) if moon > costa else np.inf,
                            HYBRID_BACK_FRACTION))
    return checks


def _summary(curves: dict[str, AlmucantarCurve], reading: AlmucantarCurve | None) -> str:
    parts = ", ".join(f"{_label(n)} {c.forward_ratio:.1f} / {c.back_ratio:.3f}"
                      for n, c in curves.items())
    text = (
        f"Sky radiance at {WAVELENGTH_NM:g} nm seen from the ground along the sun's "
        f"almucantar, the sun {SUN_ELEVATION_DEG:g} deg high (Monte Carlo, all orders), for "
        "the Mars dust models of Meyran 2022, as in the thesis's comparison with Mars Pathfinder "
        "(Tomasko et al. 1999; the thesis's Fig. 5.2). **The measured Pathfinder curves are "
        "not available here as numbers, so there is no comparison with the measurement**: "
        "the checks are the thesis's findings on the shape of each model's curve. Forward "
        f"peak L(5)/L(90) / back-scatter ratio L(180)/L(150): {parts or 'no model loaded'}.")
    if curves:
        text += (" Brightest away from the sun (mean over 30-180 deg): "
                 f"{_brightest_away_from_the_sun(curves)}")
        if reading is not None:
            text += (" of the presets; with Collienne's gas coefficients reversed: "
                     f"{_brightest_away_from_the_sun(curves | {READING: reading})}")
        text += " (the thesis: Collienne)."
    worst = [(n, c) for n, c in curves.items() if c.tables is not None]
    if worst:
        n, c = max(worst, key=lambda p: float(np.max(np.abs(p[1].tables / p[1].radiance - 1))))
        i = int(np.argmax(np.abs(c.tables / c.radiance - 1)))
        text += (f" The precomputed tables differ from the Monte Carlo by up to "
                 f"{100 * (c.tables[i] / c.radiance[i] - 1):+.0f} % ({_label(n)}, "
                 f"{c.azimuth_deg[i]:g} deg from the sun; second table).")
    return text


def _table(curves: dict[str, AlmucantarCurve]) -> Table:
    show = (0.0, FORWARD_DEG, 30.0, SIDE_DEG, BEFORE_BACK_DEG, BACK_DEG)
    rows = []
    for n, c in curves.items():
        f, fe = c.ratio(FORWARD_DEG, SIDE_DEG)
        b, be = c.ratio(BACK_DEG, BEFORE_BACK_DEG)
        rows.append([_label(n), f"{c.dust_optical_depth:.3f}"]
                    + [f"{c.at(a):.4g}" for a in show] + [f"{f:.2f} +- {fe:.2f}",
                                                          f"{b:.3f} +- {be:.3f}"])
    header = (["model", f"dust tau({WAVELENGTH_NM:g} nm)"]
              + [f"L({a:g}) [W m-2 sr-1 nm-1]" for a in show]
              + ["L(5)/L(90)", "L(180)/L(150)"])
    gamma = float(angle_from_sun_deg(SUN_ELEVATION_DEG, FORWARD_DEG, SUN_ELEVATION_DEG))
    return Table(f"Sky radiance at {WAVELENGTH_NM:g} nm along the almucantar, sun "
                 f"{SUN_ELEVATION_DEG:g} deg high, by azimuth from the sun (Monte Carlo; "
                 f"azimuth 5 deg = {gamma:.2f} deg from the sun; +- one standard error)",
                 header, rows)


def _tables_table(curves: dict[str, AlmucantarCurve]) -> Table:
    rows = []
    for n, c in curves.items():
        cells = []
        for a in TABLE_ANGLES_DEG:
            i = int(np.argmin(np.abs(c.azimuth_deg - a)))
            cells.append(f"{100 * (c.tables[i] / c.radiance[i] - 1):+.1f} %")
        rows.append([_label(n)] + cells)
    return Table("Precomputed tables (each preset's orders) / Monte Carlo - 1 along the same "
                 "almucantar: how well the tables' multiple scattering holds the forward peak "
                 "of Mie dust",
                 ["model"] + [f"{a:g} deg" for a in TABLE_ANGLES_DEG], rows)


def _notes(curves: dict[str, AlmucantarCurve], quick: bool) -> list[str]:
    notes = [
        "The measured Pathfinder radiances (Tomasko et al. 1999, sol 11, 444 nm) are not "
        "available to this suite as numbers: the thesis shows them only as curves in its "
        "Fig. 5.2, and no digitised copy is available. No absolute comparison is made and no "
        "measured value is plotted. The thesis finds that all four models are darker than "
        "the measurement at all angles (its §5.1.1).",
        "The checks restate the thesis's findings on the curves' shapes; they test that the "
        "presets reproduce the thesis's models, not that the models match Mars.",
        "The radiance is the Monte Carlo solver's (exact up to its noise), not the tables': "
        "the forward peak of Mie dust is narrower than the tables' angular cells, which "
        "their orders >= 2 must approximate (standard mode: second table).",
    ]
    if quick:
        notes.append(f"Quick mode: {QUICK_PATHS} paths per direction ({QUICK_CHECK_PATHS} at "
                     f"the checked azimuths) and {len(QUICK_AZIMUTHS_DEG)} azimuths, no tables "
                     f"(standard: {PATHS} / {CHECK_PATHS} paths, {len(AZIMUTHS_DEG)} azimuths).")
    return notes


def _figure(curves: dict[str, AlmucantarCurve], reading: AlmucantarCurve | None,
            settings: ValidationSettings) -> Figure:
    figure, axis = new_figure(1, 1, width_in=6.4, height_in=4.2)
    for name, curve in curves.items():
        colour = MODEL_COLOURS.get(name)
        axis.plot(curve.azimuth_deg, curve.radiance, "-", lw=1.6, color=colour,
                  label=f"{_label(name)} (L5/L90 {curve.forward_ratio:.1f})")
        if curve.tables is not None:
            axis.plot(curve.azimuth_deg, curve.tables, "--", lw=0.8, color=colour)
    if reading is not None:
        axis.plot(reading.azimuth_deg, reading.radiance, ":", lw=1.4,
                  color=MODEL_COLOURS["mars-collienne"], label=reading.model)
    axis.set_yscale("log")
    axis.set_xlim(0.0, 180.0)
    axis.set_xlabel("azimuth from the sun along the almucantar [deg]")
    axis.set_ylabel(f"sky radiance at {WAVELENGTH_NM:g} nm [W m-2 sr-1 nm-1]")
    tables = " (dashed: precomputed tables)" if any(c.tables is not None
                                                    for c in curves.values()) else ""
    axis.set_title(f"Mars, sun {SUN_ELEVATION_DEG:g} deg high, Monte Carlo{tables}; measured "
                   "curves not available", fontsize=8)
    axis.grid(alpha=0.3, which="both")
    axis.legend(fontsize=8)
    name = save_figure(figure, settings.output_dir, "mars_pathfinder_almucantar.png")
    return Figure(name, f"Sky radiance along the almucantar at {WAVELENGTH_NM:g} nm, sun "
                        f"{SUN_ELEVATION_DEG:g} deg high: the four dust models' forward peaks "
                        "and back scatter (the thesis's Fig. 5.2 without the measurement).")
