"""The blue glow around the setting sun on Mars (Meyran 2022, §3.3.1 and §5.2).

Ehlers, Chakrabarty & Moosmüller (2014), "Blue moons and Martian sunsets", Appl. Opt. 53, 1808,
doi:10.1364/AO.53.001808 (as quoted by Meyran 2022, §3.3.1): near-forward scattering
by the dust, stronger at short wavelengths, makes a blue cone that "dominates up to 10 deg
around the Sun and decreases up to 28 deg". The thesis compares its renders with Spirit's
sunset of sol 489 (sun 1 deg high) and InSight's of sol 1198 (2 to -2 deg): Collienne's model
is blue along the whole horizon, Costa's glow is concentrated but too blue, Blue Moon's and the
hybrid show a blue tint around the sun, the hybrid closest to the photographs (Meyran 2022,
§5.1.2 and §5.2, Figs. 5.8, 5.12, 5.13).

Here, with the sun 2 deg high: CIE 1931 x, y and McCamy's correlated colour temperature of the
sky (Monte Carlo, all orders) along the sun's almucantar (the horizon, 2 deg up; angles from
the sun 2-120 deg) and along the vertical above the sun (2-60 deg from it). The glow's strength
is dx = x(30 deg) - x(3 deg) (positive: bluer near the sun), its size the half-blueness
radius, where x has come halfway from x(3 deg) to x(30 deg) (`mars_models.half_radius_deg`).
In standard mode the case also reports dx from the precomputed tables, to show how well they
hold the forward peak of Mie dust (see the Pathfinder case).

Public names: `KEY`, `GlowProfile`, `glow_profiles`, `run`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from skyscatter.spectrum.colour import cct_mccamy_1992
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.validate.mars_models import (
    MODEL_COLOURS,
    MODEL_LABELS,
    almucantar_azimuth_deg,
    half_radius_deg,
    load_models,
    mars_solver,
    monte_carlo_solver,
    sky_chromaticity,
    sky_direction,
)
from skyscatter.validate.plots import new_figure, save_figure
from skyscatter.validate.report import CaseResult, Check, Figure, Table, ValidationSettings

__all__ = ["KEY", "GlowProfile", "glow_profiles", "run"]

KEY = "mars-blue-aureole"
SUN_ELEVATION_DEG = 2.0  # InSight sol 1198: 2 to -2 deg; Spirit sol 489: 1 deg (Meyran 2022 §5.2)
ANGLES_DEG = (2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.5, 15.0, 20.0, 25.0, 30.0, 40.0, 60.0, 90.0,
              120.0)
QUICK_ANGLES_DEG = (3.0, 4.0, 5.0, 7.5, 10.0, 15.0, 20.0, 30.0, 60.0, 90.0)
VERTICAL_MAX_DEG = 60.0
NEAR_DEG, FAR_DEG = 3.0, 30.0  # the glow: x(30) - x(3)
SPREAD_DEG = (5.0, 90.0)  # along the horizon: x(90) - x(5), the blue of the whole horizon
EHLERS_DEG = (10.0, 28.0)  # "dominates up to 10 deg ... decreases up to 28 deg"
GLOW_MODELS = ("mars-costa", "mars-bluemoon", "mars-hybrid")  # a blue glow (Meyran 2022 §5.2)
GLOW_LIMIT = 0.01  # x(30) - x(3) at least this
RADIUS_RANGE_DEG = (3.0, 30.0)  # the hybrid's half-blueness radius
# "Blue" for Collienne's horizon: bluer than D65 (McCamy CCT of D65's chromaticity), the white
# of the sRGB display that the thesis's renders (no white balance) were shown on.
D65_CCT_K = 6504.0
BANDS, QUICK_BANDS = 16, 8
# Monte Carlo paths per direction and band; standard error of x about 0.001 at 8000 (16 bands)
PATHS, QUICK_PATHS = 8_000, 3_000


@dataclass(frozen=True)
class GlowProfile:
    """Sky colour against the angle from the sun along one path."""

    model: str
    path: str  # "almucantar" or "vertical"
    angle_deg: np.ndarray  # (n,) from the sun, ascending
    xy: np.ndarray  # (n, 2)
    tables_xy: np.ndarray | None = None  # (n, 2) from the precomputed tables, if computed

    @property
    def cct_k(self) -> np.ndarray:
        """McCamy correlated colour temperature (n,). [K]"""
        return cct_mccamy_1992(self.xy)

    def x_at(self, angle_deg: float) -> float:
        return float(np.interp(angle_deg, self.angle_deg, self.xy[:, 0]))

    def y_at(self, angle_deg: float) -> float:
        return float(np.interp(angle_deg, self.angle_deg, self.xy[:, 1]))

    @property
    def delta_x(self) -> float:
        """x(30 deg) - x(3 deg): > 0 when the sky near the sun is bluer. [-]"""
        return self.x_at(FAR_DEG) - self.x_at(NEAR_DEG)

    @property
    def delta_y(self) -> float:
        """y(30 deg) - y(3 deg). [-]"""
        return self.y_at(FAR_DEG) - self.y_at(NEAR_DEG)

    @property
    def half_radius_deg(self) -> float:
        """Angle where x is halfway from x(3 deg) to x(30 deg). [deg]"""
        return half_radius_deg(self.angle_deg, self.xy[:, 0], NEAR_DEG, FAR_DEG)

    @property
    def tables_delta_x(self) -> float:
        """x(30 deg) - x(3 deg) from the tables (NaN without them). [-]"""
        if self.tables_xy is None:
            return float("nan")
        x = self.tables_xy[:, 0]
        return float(np.interp(FAR_DEG, self.angle_deg, x) - np.interp(NEAR_DEG, self.angle_deg,
                                                                       x))


def glow_profiles(solver, model: str, *, sun_elevation_deg: float = SUN_ELEVATION_DEG,
                  angles_deg=ANGLES_DEG, vertical_max_deg: float = VERTICAL_MAX_DEG,
                  tables=None) -> tuple[GlowProfile, GlowProfile]:
    """Sky chromaticity from the ground with the sun `sun_elevation_deg` [deg] high, along its
    almucantar and along the vertical above it, at `angles_deg` [deg] from the sun, from
    `solver` (and from a second solver `tables`, if given)."""
    angles = np.asarray(angles_deg, dtype=np.float64)
    sun = sky_direction(sun_elevation_deg, 0.0)
    up = angles[angles <= vertical_max_deg]
    paths = (("almucantar", angles, sky_direction(np.full(angles.shape, sun_elevation_deg),
                                                  almucantar_azimuth_deg(angles,
                                                                         sun_elevation_deg))),
             ("vertical", up, sky_direction(sun_elevation_deg + up, np.zeros(up.shape))))
    return tuple(GlowProfile(model, path, a, sky_chromaticity(solver, views, sun),
                             None if tables is None else sky_chromaticity(tables, views, sun))
                 for path, a, views in paths)


def run(settings: ValidationSettings) -> CaseResult:
    """The blue-glow case of `skyscatter validate` (module docstring)."""
    start = time.perf_counter()
    models = load_models()
    quick = settings.quick
    grid = wavelength_grid(QUICK_BANDS if quick else BANDS)
    angles = QUICK_ANGLES_DEG if quick else ANGLES_DEG
    profiles: dict[str, tuple[GlowProfile, GlowProfile]] = {}
    for name in models.names:
        atmosphere = models.atmospheres[name]
        solver = monte_carlo_solver(atmosphere, grid, settings,
                                    QUICK_PATHS if quick else PATHS)
        tables = None if quick else mars_solver(atmosphere, grid, settings)
        profiles[name] = glow_profiles(solver, name, angles_deg=angles, tables=tables)
    result = CaseResult(KEY, "Mars blue glow around the setting sun", _summary(profiles))
    result.tables = [_table(profiles)]
    result.metrics = {
        "sun_elevation_deg": SUN_ELEVATION_DEG, "bands": int(grid.size),
        "solver": "montecarlo", "paths_per_direction_and_band": QUICK_PATHS if quick else PATHS,
        "skipped": dict(models.missing),
        "profiles": {n: {p.path: {"angle_deg": p.angle_deg.tolist(), "xy": p.xy.tolist(),
                                  "cct_k": p.cct_k.tolist(), "delta_x": p.delta_x,
                                  "delta_y": p.delta_y, "half_radius_deg": p.half_radius_deg,
                                  "tables_delta_x": p.tables_delta_x}
                             for p in pair} for n, pair in profiles.items()},
        "horizon_delta_x_5_90": {n: _spread(pair[0]) for n, pair in profiles.items()},
    }
    for name in GLOW_MODELS:
        if name not in profiles:
            continue
        for p in profiles[name]:
            result.checks.append(Check(
                f"{MODEL_LABELS[name]}, {p.path}: x({NEAR_DEG:g} deg) - x({FAR_DEG:g} deg) "
                "(negative: bluer near the sun)", -p.delta_x, -GLOW_LIMIT))
    if "mars-hybrid" in profiles:
        low, high = RADIUS_RANGE_DEG
        for p in profiles["mars-hybrid"]:
            r = p.half_radius_deg
            result.checks.append(Check(
                f"hybrid, {p.path}: half-blueness radius ({r:.1f} deg) outside {low:g}-{high:g} "
                "deg by (negative: inside)", max(low - r, r - high), 0.0, " deg"))
    if "mars-collienne" in profiles:
        coolest = float(np.min(profiles["mars-collienne"][0].cct_k))
        result.checks.append(Check(
            f"Collienne is blue along the whole horizon: D65's {D65_CCT_K:g} K - its lowest CCT "
            f"at 2-{profiles['mars-collienne'][0].angle_deg[-1]:g} deg from the sun "
            f"({coolest:.0f} K)", D65_CCT_K - coolest, 0.0, " K"))
    if profiles:
        result.figures = [_figure(profiles, settings)]
    result.notes = models.notes() + _notes(profiles, quick)
    result.seconds = time.perf_counter() - start
    return result


def _spread(along: GlowProfile) -> float:
    """x(90 deg) - x(5 deg) along the horizon. [-]"""
    return along.x_at(SPREAD_DEG[1]) - along.x_at(SPREAD_DEG[0])


def _summary(profiles: dict[str, tuple[GlowProfile, GlowProfile]]) -> str:
    each = "; ".join(
        f"{MODEL_LABELS[n]} dx {a.delta_x:+.3f} / {v.delta_x:+.3f}, radius "
        f"{a.half_radius_deg:.1f} / {v.half_radius_deg:.1f} deg"
        for n, (a, v) in profiles.items())
    return (
        f"Sky colour (CIE 1931 x, y; McCamy CCT) with the sun {SUN_ELEVATION_DEG:g} deg high, "
        "along the horizon (the sun's almucantar) and along the vertical above the sun, "
        "against Ehlers et al.'s description of the Martian blue sunset glow (a blue cone "
        "dominating to 10 deg from the sun, fading out by 28 deg) and the thesis's comparison "
        "with Spirit's and InSight's sunsets. Glow strength dx = x(30) - x(3) and half-blueness "
        f"radius, horizon / vertical: {each or 'no model loaded'}. There is no measured "
        "chromaticity to compare with: the photographs are not colour-calibrated.")


def _table(profiles: dict[str, tuple[GlowProfile, GlowProfile]]) -> Table:
    rows = []
    for name, pair in profiles.items():
        for p in pair:
            spread = f"{_spread(p):+.4f}" if p.path == "almucantar" else ""
            coolest = (f"{np.min(p.cct_k):.0f}" if p.path == "almucantar" else "")
            rows.append([MODEL_LABELS[name], p.path, f"{p.x_at(NEAR_DEG):.4f}",
                         f"{p.x_at(FAR_DEG):.4f}", f"{p.delta_x:+.4f}", f"{p.delta_y:+.4f}",
                         f"{np.interp(NEAR_DEG, p.angle_deg, p.cct_k):.0f}",
                         f"{np.interp(FAR_DEG, p.angle_deg, p.cct_k):.0f}",
                         f"{p.half_radius_deg:.1f}", spread, coolest,
                         "" if p.tables_xy is None else f"{p.tables_delta_x:+.4f}"])
    return Table(f"Sky colour near the sun {SUN_ELEVATION_DEG:g} deg high (Monte Carlo): x, CCT "
                 "at 3 and 30 deg from the sun, the glow dx, dy, its half-blueness radius; along "
                 "the horizon x(90) - x(5) and the lowest CCT at 2-120 deg; dx from the tables",
                 ["model", "path", "x(3)", "x(30)", "dx", "dy", "CCT(3) [K]", "CCT(30) [K]",
                  "half radius [deg]", "horizon x(90)-x(5)", "horizon min CCT [K]",
                  "dx (tables)"], rows)


def _notes(profiles: dict[str, tuple[GlowProfile, GlowProfile]], quick: bool) -> list[str]:
    coolest = [float(np.min(pair[0].cct_k)) for n, pair in profiles.items()
               if n != "mars-collienne"]
    others = (f" The other models' horizons are orange (lowest CCT {min(coolest):.0f}-"
              f"{max(coolest):.0f} K)." if coolest else "")
    notes = [
        "The half-blueness radius is taken between 3 and 30 deg, as Ehlers' 28 deg edge "
        "suggests; where x rises monotonically it lies between them by construction, so the "
        "radius check mainly says that a glow exists and is not flat; the radius itself (how "
        "far in the 3-30 deg range the blue reaches) is the information.",
        "Collienne's 'blue along the whole horizon' (Meyran 2022 §5.2): x(90) - x(5) along the "
        "horizon is reported, not checked, because it measures how much the colour changes, "
        "not whether it is blue (Blue Moon's changes least and is orange). The claim is about "
        "the colour itself in renders without white balance on an sRGB display, so it is "
        "checked as: the whole horizon bluer than D65 (lowest CCT > 6504 K), which the "
        "preset's order of Collienne's coefficients gives." + others,
    ]
    if quick:
        notes.append(f"Quick mode: {QUICK_BANDS} bands, {QUICK_PATHS} paths, "
                     f"{len(QUICK_ANGLES_DEG)} angles, no tables (standard: {BANDS} bands, "
                     f"{PATHS} paths, {len(ANGLES_DEG)} angles).")
    return notes


def _figure(profiles: dict[str, tuple[GlowProfile, GlowProfile]],
            settings: ValidationSettings) -> Figure:
    figure, axes = new_figure(2, 2, width_in=4.6, height_in=3.4)
    for column, path in enumerate(("almucantar", "vertical")):
        for name, pair in profiles.items():
            p = pair[column]
            style = {"ms": 2.5, "lw": 1.4, "color": MODEL_COLOURS.get(name),
                     "label": MODEL_LABELS[name]}
            axes[0][column].plot(p.angle_deg, p.xy[:, 0], "o-", **style)
            axes[1][column].plot(p.angle_deg, p.cct_k, "o-", **style)
        where = ("along the horizon (almucantar)" if path == "almucantar"
                 else "along the vertical above the sun")
        axes[0][column].set_title(f"sun {SUN_ELEVATION_DEG:g} deg high, {where}", fontsize=9)
        for row in (0, 1):
            axis = axes[row][column]
            for edge in EHLERS_DEG:
                axis.axvline(edge, color="0.6", lw=0.8, ls=":")
            axis.set_xscale("log")
            largest = max(float(pair[column].angle_deg[-1]) for pair in profiles.values())
            ticks = [t for t in (2, 3, 5, 10, 20, 30, 60, 120) if t <= largest]
            axis.set_xticks(ticks, [str(t) for t in ticks])
            axis.minorticks_off()
            axis.set_xlabel("angle from the sun [deg] (dotted: Ehlers' 10 and 28 deg)",
                            fontsize=8)
            axis.grid(alpha=0.3, which="both")
        axes[0][column].set_ylabel("CIE 1931 x (lower: bluer)", fontsize=8)
        axes[1][column].set_ylabel("McCamy CCT [K]", fontsize=8)
    axes[0][0].legend(fontsize=7)
    name = save_figure(figure, settings.output_dir, "mars_blue_aureole.png")
    return Figure(name, "The blue glow around the setting sun: chromaticity x and colour "
                        "temperature against the angle from the sun, along the horizon and "
                        "up the vertical.")
