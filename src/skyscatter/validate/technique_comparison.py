"""`skyscatter compare`: sky models side by side against the Monte Carlo reference, in the
manner of Pinheiro's study of Bruneton's and Schüler's techniques (2014, ch. 6) and Bruneton's
evaluation of clear-sky models (E. Bruneton, "A Qualitative and Quantitative Evaluation of 8
Clear Sky Models", IEEE TVCG 23(12), 2641-2655, 2017, doi:10.1109/TVCG.2016.2622272).

For each solver, atmosphere and sun zenith: the sky radiance seen from the ground on a fixed
grid of view directions (`lut_vs_montecarlo.sky_grid`) against the Monte Carlo mean of the
same optical profile (`lut_vs_montecarlo.reference_solver`, the same reference the
validation suite uses), summarised by `lut_vs_montecarlo.SolverComparison` (median and 95th
percentile of |L / L_MC - 1| per band, the Monte Carlo's relative standard error), plus the
luminance Y and the CIE 1931 chromaticity (x, y) of the spectra (`spectrum.colour`); per
solver and atmosphere: the precompute time (building the solver and its first answer), the CPU
and wall time of one frame and the peak memory traced by `tracemalloc` over both (numpy's
arrays; numba's own allocations are not traced). A solver that refuses a case (its
`SolverDomain`, `transport.ground_sky`: an InputError) is reported "n/a (domain)" with its
reason.

The Monte Carlo means are kept in the cache (`disk_cache.TableCache`, atomic .npz entries) under
a key of the optical profile, sun zenith, view grid, paths, seed, package version and the
Monte Carlo code's fingerprint, so a rerun traces no path again.

Public names: `ComparisonPlan`, `comparison_plan`, `MethodCase`, `MethodCost`,
`ComparisonResult`, `run_comparison`, `DEFAULT_SOLVERS`, `DEFAULT_ATMOSPHERES`,
`DEFAULT_SUN_ZENITHS_DEG`.
"""

from __future__ import annotations

import hashlib
import json
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from skyscatter import __version__
from skyscatter.atmosphere.model import Atmosphere, OpticalProfile
from skyscatter.atmosphere.variants import load_variant
from skyscatter.errors import InputError
from skyscatter.jit_cache import kernel_cache_folder
from skyscatter.render.camera import EquirectangularCamera
from skyscatter.render.scene import ground_viewpoint, render_sky
from skyscatter.spectrum.colour import spectral_to_xyz, xy_chromaticity
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.cache import profile_fingerprint
from skyscatter.transport.code_fingerprint import code_fingerprint
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import (
    SOLVERS,
    Solver,
    SolverOptions,
    SurfaceRadianceSolver,
    SurfaceSolver,
    make_solver,
    solver_domain,
)
from skyscatter.validate.comparison_figures import error_figure, fisheye_figure
from skyscatter.validate.comparison_report import NOT_IN_DOMAIN, write_comparison_report
from skyscatter.validate.lut_vs_montecarlo import (
    PEAKED_TARGET_ERROR,
    SkyGrid,
    SolverComparison,
    reference_solver,
    sky_grid,
)

__all__ = [
    "DEFAULT_ATMOSPHERES",
    "DEFAULT_SOLVERS",
    "DEFAULT_SUN_ZENITHS_DEG",
    "ComparisonPlan",
    "ComparisonResult",
    "MethodCase",
    "MethodCost",
    "comparison_plan",
    "run_comparison",
]

# every registered solver but the reference itself and the ray-marched single scattering
DEFAULT_SOLVERS = ("lut", "hillaire", "schuler", "bruneton-simplified", "cie", "preetham")
# Earth clear; Earth hazy: the earth preset's aerosol x 4 (optical depth 0.1 -> 0.4 at 500 nm,
# no hazy Earth preset exists: earth-overcast and earth-fog are clouds); Mars with Mie dust
DEFAULT_ATMOSPHERES = ("earth", "earth:aerosol*4", "mars-physical")
DEFAULT_SUN_ZENITHS_DEG = (0.0, 30.0, 60.0, 80.0, 94.0)
# a panorama of 2^17 rays before the timed frame: it compiles the kernels the frame needs
# (Hillaire's sky-view table serves frames of >= 2^16 rays), so that the frame is timed warm
WARM_UP_FRAME = (512, 256)
FRAME_SUN_ZENITH_DEG = 60.0  # the frames and fisheyes: the daytime sun nearest this


@dataclass(frozen=True)
class ComparisonPlan:
    """What a comparison covers and at what cost.

    solvers            names (`transport.solvers.SOLVERS`)
    atmospheres        presets, configs or variants (`atmosphere.variants.load_variant`)
    sun_zeniths_deg    the sun's zenith angles [deg]; > 90: twilight
    grid               view directions from the ground, azimuth from the sun's
    n_wavelengths      bands over 360-830 nm (`spectrum.grid.wavelength_grid`)
    day_paths          Monte Carlo paths per direction and band, sun up
    twilight_paths     the same with the sun below the horizon (noisier: more paths)
    frame_size         (width, height) of the timed frame, a panorama [pixels]
    frame_scale        the timed frame's pixels x this = a 1920 x 1080 frame (1: it is one)
    fisheye_size       side of the fisheye renders of the figure [pixels]
    fresh_tables       precompute the tables of "lut" and "bruneton-simplified" afresh (their
                       time is the precompute time) rather than load them from the cache
    target_relative_error  by day in forward-peaked media, the Monte Carlo adds paths up to this
                       relative standard error (`lut_vs_montecarlo.reference_solver`); None: not
    quick              the reduced plan of the tests (`--quick`)
    """

    solvers: tuple[str, ...]
    atmospheres: tuple[str, ...]
    sun_zeniths_deg: tuple[float, ...]
    grid: SkyGrid
    n_wavelengths: int
    day_paths: int
    twilight_paths: int
    frame_size: tuple[int, int]
    frame_scale: float
    fisheye_size: int
    fresh_tables: bool
    target_relative_error: float | None = None
    quick: bool = False

    def paths(self, sun_zenith_deg: float) -> int:
        return self.day_paths if sun_zenith_deg <= 90.0 else self.twilight_paths

    @property
    def frame_sun_zenith_deg(self) -> float:
        """The daytime sun of the frames and fisheyes: the plan's nearest FRAME_SUN_ZENITH_DEG
        (the lowest of all when none is up)."""
        day = [z for z in self.sun_zeniths_deg if z < 90.0] or [min(self.sun_zeniths_deg)]
        return min(day, key=lambda z: abs(z - FRAME_SUN_ZENITH_DEG))


def comparison_plan(quick: bool = False, solvers: Sequence[str] | None = None,
                    atmospheres: Sequence[str] | None = None,
                    sun_zeniths_deg: Sequence[float] | None = None, *,
                    paths: int | None = None) -> ComparisonPlan:
    """The standard plan (11 view zeniths 0-85 deg x 5 azimuths 0-180 deg, 8 bands, 4000 /
    10 000 paths by day / in twilight, a 1920 x 1080 frame, tables afresh) or the `quick` one
    (4 x 3 directions, 2 bands, 2000 / 5000 paths, a 384 x 216 frame scaled x 25, tables from
    the cache); `paths` replaces the daytime paths (twilight: 2.5 x). InputError for an
    unknown solver, a sun zenith outside 0-180 deg or paths outside 100-10^6."""
    names = tuple(DEFAULT_SOLVERS if solvers is None else solvers)
    unknown = [n for n in names if n not in SOLVERS]
    if unknown or not names:
        raise InputError(f"unknown solver {unknown[0]!r} in --solvers; available: "
                         f"{', '.join(SOLVERS)}" if unknown else "--solvers is empty",
                         key="solvers", value=",".join(names), allowed=", ".join(SOLVERS))
    if "montecarlo" in names:
        raise InputError("--solvers: montecarlo is the reference every solver is compared "
                         "with; leave it out", key="solvers", value="montecarlo")
    zeniths = tuple(float(z) for z in (DEFAULT_SUN_ZENITHS_DEG if sun_zeniths_deg is None
                                       else sun_zeniths_deg))
    if not zeniths or not all(0.0 <= z <= 180.0 for z in zeniths):
        raise InputError(f"--sun-zeniths {zeniths} is not allowed: angles in 0-180 deg",
                         key="sun_zeniths", value=zeniths, allowed="0-180 deg")
    if paths is not None and not 100 <= paths <= 1_000_000:
        raise InputError(f"--paths {paths} is not allowed: 100 to 1000000 per direction and "
                         "band", key="paths", value=paths, allowed="100-1000000")
    chosen = tuple(DEFAULT_ATMOSPHERES if atmospheres is None else atmospheres)
    if quick:
        day = paths or 2000
        return ComparisonPlan(names, chosen, zeniths,
                              sky_grid((0.0, 30.0, 60.0, 85.0), (0.0, 90.0, 180.0)), 2, day,
                              int(2.5 * day), (384, 216), 25.0, 48, fresh_tables=False,
                              quick=True)
    day = paths or 4000
    return ComparisonPlan(names, chosen, zeniths,
                          sky_grid((0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 75.0, 80.0,
                                    85.0), (0.0, 45.0, 90.0, 135.0, 180.0)),
                          8, day, int(2.5 * day), (1920, 1080), 1.0, 160, fresh_tables=True,
                          target_relative_error=PEAKED_TARGET_ERROR)


@dataclass(frozen=True)
class MethodCase:
    """One solver, atmosphere and sun: its comparison with the Monte Carlo reference, or why
    it has none (`domain`: the solver's one-line refusal)."""

    solver: str
    atmosphere: str
    sun_zenith_deg: float
    comparison: SolverComparison | None = None
    domain: str | None = None

    @property
    def luminance_error(self) -> np.ndarray:
        """|Y / Y_MC - 1| per direction (n,); NaN where the reference is dark."""
        c = self.comparison
        y = spectral_to_xyz(c.tables, c.wavelengths_nm)[:, 1]
        y_mc = spectral_to_xyz(c.monte_carlo, c.wavelengths_nm)[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(y_mc > 0.0, np.abs(y / y_mc - 1.0), np.nan)

    @property
    def chromaticity_error(self) -> np.ndarray:
        """Distance in CIE 1931 (x, y) from the reference's chromaticity per direction (n,)."""
        c = self.comparison
        xy = xy_chromaticity(spectral_to_xyz(c.tables, c.wavelengths_nm))
        xy_mc = xy_chromaticity(spectral_to_xyz(c.monte_carlo, c.wavelengths_nm))
        return np.hypot(*(xy - xy_mc).T)


@dataclass(frozen=True)
class MethodCost:
    """What one solver costs for one atmosphere (None: it refused the frame's case)."""

    solver: str
    atmosphere: str
    precompute_wall_s: float | None = None
    precompute_cpu_s: float | None = None
    tables_cached: bool = False  # its tables came from the cache, not computed here
    frame_wall_s: float | None = None  # scaled to 1920 x 1080 (`ComparisonPlan.frame_scale`)
    frame_cpu_s: float | None = None
    peak_traced_mib: float | None = None
    domain: str | None = None


@dataclass
class ComparisonResult:
    """Everything `run_comparison` measured, and the files it wrote."""

    plan: ComparisonPlan
    wavelengths_nm: np.ndarray
    cases: list[MethodCase] = field(default_factory=list)
    costs: list[MethodCost] = field(default_factory=list)
    capabilities: dict[str, dict[str, bool]] = field(default_factory=dict)
    reference_seconds: float = 0.0  # Monte Carlo time of this run (0 for cached means)
    reference_cached: int = 0  # cases whose Monte Carlo means came from the cache
    files: list[Path] = field(default_factory=list)


def _monte_carlo_code(profile: OpticalProfile) -> str:
    """Fingerprint of the Monte Carlo code that traces `profile` (its call graph and the
    classes of its phase functions, as the tables' cache keys theirs): a changed tracer makes
    new references, with or without a new version."""
    phases = sorted({(type(phase).__module__, type(phase).__name__)
                     for phase in profile.phases if phase is not None})
    return code_fingerprint((("skyscatter.transport.monte_carlo", "MonteCarloSolver"),
                             *phases), (kernel_cache_folder(),))


def _reference_key(profile: OpticalProfile, sun_zenith_deg: float, grid: SkyGrid, paths: int,
                   seed: int, target: float | None) -> tuple[str, dict]:
    """(cache key, metadata) of one Monte Carlo reference."""
    metadata = {"what": "Monte Carlo sky radiance (skyscatter compare)",
                "profile": profile_fingerprint(profile), "sun_zenith_deg": sun_zenith_deg,
                "view_zenith_deg": grid.view_zenith_deg.tolist(),
                "azimuth_deg": grid.azimuth_deg.tolist(), "paths": paths, "seed": seed,
                "target_relative_error": target, "version": __version__,
                "code": _monte_carlo_code(profile)}
    digest = hashlib.sha256(json.dumps(metadata, sort_keys=True).encode()).hexdigest()
    return f"montecarlo-{digest[:32]}", metadata


def _monte_carlo(atmosphere: str, profile: OpticalProfile, sun_zenith_deg: float,
                 plan: ComparisonPlan, *, seed: int, cache) -> tuple[np.ndarray, np.ndarray,
                                                                    float, bool]:
    """(mean, standard error, seconds, from the cache) of the reference on the plan's grid."""
    paths = plan.paths(sun_zenith_deg)
    target = plan.target_relative_error if sun_zenith_deg < 90.0 else None
    key, metadata = _reference_key(profile, sun_zenith_deg, plan.grid, paths, seed, target)
    if cache is not None:
        arrays, _ = cache.load(key, metadata)
        if arrays is not None:
            return arrays["mean"], arrays["standard_error"], 0.0, True
    solver = reference_solver(profile, atmosphere, sun_zenith_deg, paths, seed=seed,
                              target_relative_error=target)
    start = time.perf_counter()
    mean, error = solver.sky_radiance_with_error(
        observer_position(0.0, profile.bottom_radius_m), plan.grid.directions,
        local_frame_directions(np.radians(sun_zenith_deg), 0.0))
    seconds = time.perf_counter() - start
    if cache is not None and cache.check_writable() is None:
        cache.store(key, {"mean": mean, "standard_error": error}, metadata)
    return mean, error, seconds, False


def _options(name: str, atmosphere: Atmosphere, plan: ComparisonPlan, cache,
             messages: list[str]) -> SolverOptions:
    """The solver's options: the atmosphere's orders, the run's cache, fresh tables where the
    plan says (not for "cie", which borrows "lut"'s zenith: its tables are "lut"'s)."""
    return SolverOptions(orders=atmosphere.scattering_orders, cache=cache,
                         force=plan.fresh_tables and name in ("lut", "bruneton-simplified"),
                         log=messages.append)


def _timed(function: Callable[[], object]) -> tuple[object, float, float]:
    """(result, wall [s], CPU [s] of all threads of this process) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def _build(name: str, atmosphere: Atmosphere, profile: OpticalProfile, plan: ComparisonPlan,
           cache) -> tuple[Solver | None, MethodCost]:
    """The solver and its cost (precompute, one frame, traced peak memory); (None, the
    refusal) outside its domain."""
    messages: list[str] = []
    frame_sun = local_frame_directions(np.radians(plan.frame_sun_zenith_deg), 0.0)
    origin = observer_position(0.0, profile.bottom_radius_m)
    tracemalloc.start()
    try:
        def prepare() -> Solver:
            solver = make_solver(name, profile, _options(name, atmosphere, plan, cache,
                                                         messages))
            solver.sky_radiance(origin, np.array([0.0, 0.0, 1.0]), frame_sun)  # lazy parts
            return solver
        solver, pre_wall, pre_cpu = _timed(prepare)
        peak = tracemalloc.get_traced_memory()[1]
        viewpoint = ground_viewpoint(0.0, profile.bottom_radius_m)
        for size in (WARM_UP_FRAME, plan.frame_size):  # the first compiles what it needs
            tracemalloc.reset_peak()
            _, frame_wall, frame_cpu = _timed(lambda size=size: render_sky(
                solver, EquirectangularCamera(*size), viewpoint, frame_sun,
                atmosphere.planet.star))
        peak = max(peak, tracemalloc.get_traced_memory()[1]) / 2**20
    except InputError as refusal:
        return None, MethodCost(name, atmosphere.name, domain=str(refusal))
    finally:
        tracemalloc.stop()
    cached = any(m.startswith("tables: using") for m in messages)
    return solver, MethodCost(name, atmosphere.name, pre_wall, pre_cpu, cached,
                              frame_wall * plan.frame_scale, frame_cpu * plan.frame_scale, peak)


def _case(solver: Solver | None, name: str, atmosphere: str, sun_zenith_deg: float,
          reference: tuple[np.ndarray, np.ndarray, float, bool], plan: ComparisonPlan,
          refusal: str | None) -> MethodCase:
    if solver is None:
        return MethodCase(name, atmosphere, sun_zenith_deg, domain=refusal)
    profile = solver.profile
    try:
        radiance = solver.sky_radiance(observer_position(0.0, profile.bottom_radius_m),
                                       plan.grid.directions,
                                       local_frame_directions(np.radians(sun_zenith_deg), 0.0))
    except InputError as error:
        return MethodCase(name, atmosphere, sun_zenith_deg, domain=str(error))
    mean, error, seconds, _ = reference
    return MethodCase(name, atmosphere, sun_zenith_deg, SolverComparison(
        atmosphere, sun_zenith_deg, profile.wavelengths_nm, plan.grid, radiance, mean, error,
        plan.paths(sun_zenith_deg), seconds))


def _capabilities(solver: Solver) -> dict[str, bool]:
    """What the solver can do, from its domain and the capability protocols."""
    domain = solver_domain(solver)
    return {"views from the air and space": not domain.ground_only,
            "twilight (sun below the horizon)": not domain.sun_above_horizon,
            "other planets": not domain.earth_only,
            "aerial perspective and ground irradiance": isinstance(solver, SurfaceSolver),
            "albedo maps, terrain, clouds": isinstance(solver, SurfaceRadianceSolver)}


def run_comparison(plan: ComparisonPlan, output_dir: str | Path, *, cache=None, seed: int = 0,
                   log: Callable[[str], None] = print,
                   step: Callable[[int, int, str], None] | None = None) -> ComparisonResult:
    """Run `plan` and write report.md, results.json and the PNG figures into `output_dir`.
    `cache` (`disk_cache.TableCache` or None) keeps the tables and the Monte Carlo means;
    `log` gets a line per atmosphere and case, `step(done, total, label)` after each
    (solver, atmosphere, sun). InputError for an atmosphere that does not load."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    atmospheres = [load_variant(spec) for spec in plan.atmospheres]
    wavelengths = wavelength_grid(plan.n_wavelengths)
    result = ComparisonResult(plan, wavelengths)
    renders: dict[str, dict[str, Solver]] = {}
    total = len(plan.solvers) * len(plan.atmospheres) * len(plan.sun_zeniths_deg)
    for spec, atmosphere in zip(plan.atmospheres, atmospheres, strict=True):
        profile = atmosphere.optical_profile(wavelengths)
        references = {}
        for sun_zenith in plan.sun_zeniths_deg:
            references[sun_zenith] = _monte_carlo(atmosphere.name, profile, sun_zenith, plan,
                                                  seed=seed, cache=cache)
            mean, error, seconds, cached = references[sun_zenith]
            result.reference_seconds += seconds
            result.reference_cached += cached
            log(f"{spec}, sun zenith {sun_zenith:g} deg: Monte Carlo "
                + ("from the cache" if cached else f"{seconds:.1f} s"))
        renders[spec] = {}
        for name in plan.solvers:
            solver, cost = _build(name, atmosphere, profile, plan, cache)
            result.costs.append(cost)
            if solver is not None:
                renders[spec][name] = solver
                result.capabilities.setdefault(name, _capabilities(solver))
            for sun_zenith in plan.sun_zeniths_deg:
                case = _case(solver, name, spec, sun_zenith, references[sun_zenith], plan,
                             cost.domain)
                result.cases.append(case)
                if step is not None:
                    step(len(result.cases), total, f"{name}, {spec}, {sun_zenith:g} deg")
            log(f"{spec}: {name} " + (NOT_IN_DOMAIN if solver is None else
                                      f"precompute {cost.precompute_cpu_s:.1f} s CPU, frame "
                                      f"{cost.frame_cpu_s:.1f} s CPU"))
    figures = [error_figure(result, out)]
    figures += [fisheye_figure(result, spec, atmosphere, solvers, out)
                for (spec, solvers), atmosphere in zip(renders.items(), atmospheres, strict=True)
                if solvers]
    result.files = write_comparison_report(result, figures, out)
    return result
