"""Cloud descriptions: layers of liquid or ice cloud read from TOML (`--clouds FILE|PRESET`).

A clouds file holds one or more `[[layer]]` tables (docs/clouds.md lists every key):

    [[layer]]
    name = "cumulus"
    type = "volume"                  # or "sheet": a thin high layer (cirrus), one sample deep
    base_altitude_m = 1200.0
    top_altitude_m = 2800.0
    coverage = 0.4                   # fraction of the sky the layer covers [0-1]
    water_content_g_m3 = 0.5         # liquid or ice water content where the cloud is densest
    profile = [[0.0, 0.0], [0.1, 1.0], [0.6, 0.9], [1.0, 0.1]]  # (height fraction, factor)
    [layer.shape]                    # procedural noise (`atmosphere.cloud_noise`)
    seed = 1
    scale_m = 9000.0                 # one tile of the shape noise
    detail_scale_m = 1500.0          # one tile of the edge-eroding detail noise
    detail_strength = 0.35           # how much the detail erodes the edges [0-1]
    edge = 0.3                       # density ramps from 0 to full over this share of the
                                     # noise values a cloud covers [0-1]: soft to sharp edges
    coverage_variation = 0.4         # coverage varies by this share over 7.3 tiles [0-1]
    stretch = 1.0                    # horizontal stretch along the wind (cirrus streaks)
    coverage_map = "weather.png"     # optional: an equirectangular map [0-1] the coverage is
                                     # multiplied by (`atmosphere.cloud_maps`), path relative
                                     # to the clouds file
    [layer.wind]
    east_m_s = 5.0
    north_m_s = 2.0
    [layer.particles]
    phase = "liquid"                 # Mie droplets; or "ice" (`optics.cloud_optics`)
    effective_radius_um = 8.0
    effective_variance = 0.1         # liquid only

A `type = "grid"` layer takes its water from a 3-D grid in a file instead of the noise
(`atmosphere.cloud_grids`; docs/clouds.md, "A grid from a file"):

    [[layer]]
    type = "grid"
    grid = "les.npz"                 # water_g_m3 (nx, ny, nz), spacing_m (dx, dy, dz),
                                     # optionally periodic; path relative to the clouds file
    base_altitude_m = 500.0          # the box's bottom; top_altitude_m = base + nz dz (optional)
    [layer.particles]                # and [layer.wind], as above; coverage, water_content_g_m3,
    ...                              # profile, [layer.shape] and coverage_map are refused

Layers may not overlap in altitude: the renderer takes them in the order a ray meets them.
Presets live in `atmosphere/cloud_presets/*.toml` and cite the observations behind their
numbers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.cloud_grids import read_cloud_grid
from skyscatter.atmosphere.cloud_maps import read_coverage_map
from skyscatter.atmosphere.config_file import preset_or_file, read_toml
from skyscatter.atmosphere.config_table import ConfigTable
from skyscatter.checks import Bounds
from skyscatter.errors import ConfigError, InputError

__all__ = [
    "CLOUD_PRESETS_DIR",
    "CloudGrid",
    "CloudLayer",
    "CloudParticles",
    "CloudShape",
    "Clouds",
    "CoverageMap",
    "list_cloud_presets",
    "load_clouds",
    "parse_clouds",
]

CLOUD_PRESETS_DIR = Path(__file__).parent / "cloud_presets"
MAX_CLOUD_LAYERS = 8  # each layer is one more march per ray
MAX_PROFILE_NODES = 32

# Ranges, each with its reason:
CLOUD_ALTITUDE_M = Bounds(0.0, 100e3)  # tropospheric to polar-mesospheric clouds (~83 km)
FRACTION = Bounds(0.0, 1.0)
EDGE = Bounds(0.01, 1.0)  # a ramp over less than 1 % of the noise is a step the march aliases
# Liquid water contents of clouds reach ~5 g m^-3 in deep convection (Pruppacher & Klett 1997,
# ch. 2); 50 leaves room for dense fog or dust and catches kg for g.
WATER_CONTENT_G_M3 = Bounds(0.0, 50.0, low_open=True)
NOISE_SCALE_M = Bounds(10.0, 1e7)  # a tile from a 10 m wisp to a planet-wide pattern
STRETCH = Bounds(0.1, 20.0)  # cirrus uncinus streaks are ~10 x longer than wide
WIND_M_S = Bounds(-200.0, 200.0)  # jet streams reach ~100 m/s; Venus' superrotation ~100 m/s
LIQUID_RADIUS_UM = Bounds(1.0, 40.0)  # `optics.cloud_optics.liquid_cloud_optics`
ICE_RADIUS_UM = Bounds(5.0, 100.0)  # `optics.cloud_optics.ice_cloud_optics`
EFFECTIVE_VARIANCE = Bounds(0.01, 0.45)  # Hansen & Travis's b; clouds 0.05-0.2
LAYER_TYPES = ("volume", "sheet", "grid")
# keys of the noise a grid layer does not read: refused rather than silently ignored
GRID_REFUSED_KEYS = ("coverage", "water_content_g_m3", "profile", "shape", "coverage_map")
PHASES = ("liquid", "ice")


@dataclass(frozen=True)
class CloudShape:
    """Procedural noise of a layer: seed, tile sizes [m], detail erosion, edge width and
    coverage variation [0-1], stretch along the wind [-] (module docstring)."""

    seed: int = 1
    scale_m: float = 9000.0
    detail_scale_m: float = 1500.0
    detail_strength: float = 0.35
    edge: float = 0.3
    coverage_variation: float = 0.4
    stretch: float = 1.0


@dataclass(frozen=True)
class CloudParticles:
    """Microphysics: "liquid" (Mie, effective radius [um] and variance) or "ice"."""

    phase: str = "liquid"
    effective_radius_um: float = 10.0
    effective_variance: float = 0.1


@dataclass(frozen=True, eq=False)
class CoverageMap:
    """An equirectangular coverage map [0-1] (h, w), row 0 at latitude +90 deg, column 0 at
    longitude -180 deg (`atmosphere.cloud_maps`), and the file it came from."""

    values: np.ndarray
    source: str = ""


@dataclass(frozen=True, eq=False)
class CloudGrid:
    """Water content on a regular grid (`atmosphere.cloud_grids`): water_g_m3 (nx, ny, nz)
    [g m^-3] at cell centres, x east, y north, z up; the cells' size (dx, dy, dz) [m];
    whether it repeats horizontally; the file it came from."""

    water_g_m3: np.ndarray
    spacing_m: tuple[float, float, float]
    periodic: bool = True
    source: str = ""


@dataclass(frozen=True)
class CloudLayer:
    """One cloud layer (module docstring); altitudes [m], water content [g m^-3], wind in the
    observer's east-north frame [m s^-1], profile nodes (height fraction 0-1, factor 0-1),
    an optional coverage map the coverage is multiplied by; a "grid" layer's water comes from
    `grid` (its `water_content_g_m3` is then the grid's largest value, its coverage 1, its
    shape and profile unused)."""

    name: str
    kind: str
    base_altitude_m: float
    top_altitude_m: float
    coverage: float
    water_content_g_m3: float
    profile: tuple[tuple[float, float], ...]
    shape: CloudShape
    particles: CloudParticles
    wind_m_s: tuple[float, float] = (0.0, 0.0)
    coverage_map: CoverageMap | None = None
    grid: CloudGrid | None = None


@dataclass(frozen=True)
class Clouds:
    """The layers of a clouds file, lowest first, and where they came from."""

    layers: tuple[CloudLayer, ...]
    name: str = ""
    description: str = ""


def list_cloud_presets() -> dict[str, str]:
    """Cloud preset name -> one-line description, sorted by name."""
    return {path.stem: str(read_toml(path).get("description", ""))
            for path in sorted(CLOUD_PRESETS_DIR.glob("*.toml"))}


def load_clouds(name_or_path: str | Path) -> Clouds:
    """Clouds of a preset (`list_cloud_presets`) or a TOML file; InputError naming the presets
    for an unknown name, ConfigError naming the key for a bad value."""
    path = preset_or_file(name_or_path, CLOUD_PRESETS_DIR, kind="cloud preset",
                          file_kind="clouds file", keys=("clouds", "clouds"))
    return parse_clouds(read_toml(path), path)


def parse_clouds(data: dict, path: Path) -> Clouds:
    """`Clouds` from the parsed TOML of a clouds file at `path` (module docstring)."""
    top = ConfigTable(dict(data), path, "")
    name = top.text("name", path.stem)
    description = top.text("description", "")
    if top.has("sources"):
        top.data.pop("sources")
    tables = top.tables("layer", MAX_CLOUD_LAYERS, "each layer is one more march per ray")
    top.finish()
    if not tables:
        raise ConfigError("a clouds file needs at least one [[layer]]", path=path, key="layer")
    layers = sorted((_parse_layer(table) for table in tables),
                    key=lambda layer: layer.base_altitude_m)
    for lower, upper in zip(layers, layers[1:], strict=False):
        if upper.base_altitude_m < lower.top_altitude_m:
            raise ConfigError(f"cloud layers '{lower.name}' ({lower.base_altitude_m:g}-"
                              f"{lower.top_altitude_m:g} m) and '{upper.name}' "
                              f"({upper.base_altitude_m:g}-{upper.top_altitude_m:g} m) overlap: "
                              "give each its own altitudes", path=path, key="layer")
    return Clouds(tuple(layers), name, description)


def _parse_layer(table: ConfigTable) -> CloudLayer:
    name = table.text("name", table.prefix)
    kind = table.text("type", "volume", LAYER_TYPES)
    if kind == "grid":
        return _parse_grid_layer(table, name)
    base = table.number("base_altitude_m", CLOUD_ALTITUDE_M)
    top = table.number("top_altitude_m", CLOUD_ALTITUDE_M)
    if not top > base:
        raise table.error("top_altitude_m", top, f"above base_altitude_m = {base:g}")
    coverage = table.number("coverage", FRACTION)
    water = table.number("water_content_g_m3", WATER_CONTENT_G_M3)
    profile = _parse_profile(table)
    coverage_map = _parse_coverage_map(table)
    shape = _parse_shape(table.table("shape", required=False))
    particles = _parse_particles(table.table("particles", required=False))
    wind = _parse_wind(table.table("wind", required=False))
    table.finish()
    return CloudLayer(name, kind, base, top, coverage, water, profile, shape, particles, wind,
                      coverage_map)


def _parse_grid_layer(table: ConfigTable, name: str) -> CloudLayer:
    """A `type = "grid"` layer (module docstring): its grid file, base, optional top (which
    must be base + nz dz), particles and wind; the noise's keys refused."""
    for key in GRID_REFUSED_KEYS:
        if table.has(key):
            raise table.error(key, table.data[key], 'not in a type = "grid" layer, which '
                              "takes its water from the grid file: remove it")
    if not table.has("grid"):
        raise table.missing("grid", ' (type = "grid" reads its water from an .npz file)')
    grid = _parse_grid(table)
    base = table.number("base_altitude_m", CLOUD_ALTITUDE_M)
    top = base + grid.water_g_m3.shape[2] * grid.spacing_m[2]
    if top > CLOUD_ALTITUDE_M.high:
        raise table.error("base_altitude_m", base, f"the grid's top (base + nz dz = {top:g} m) "
                          f"at most {CLOUD_ALTITUDE_M.high:g} m up")
    if table.has("top_altitude_m"):
        given = table.number("top_altitude_m", CLOUD_ALTITUDE_M)
        if abs(given - top) > 1e-6 * max(top, 1.0):
            raise table.error("top_altitude_m", given, f"base_altitude_m + nz dz = {top:g} (the "
                              "grid's height), or leave it out")
    particles = _parse_particles(table.table("particles", required=False))
    wind = _parse_wind(table.table("wind", required=False))
    table.finish()
    return CloudLayer(name, "grid", base, top, 1.0, float(grid.water_g_m3.max()),
                      ((0.0, 1.0), (1.0, 1.0)), CloudShape(), particles, wind, None, grid)


def _parse_grid(table: ConfigTable) -> CloudGrid:
    """The layer's `grid`, an .npz path relative to the clouds file."""
    name = table.text("grid")
    path = Path(name) if Path(name).is_absolute() else table.path.parent / name
    try:
        water, spacing, periodic = read_cloud_grid(path)
    except InputError as error:
        raise table.error("grid", name, f"{error} (the path is relative to the clouds file; "
                          "docs/clouds.md, 'A grid from a file')") from None
    return CloudGrid(water, spacing, periodic, str(path))


def _parse_wind(table: ConfigTable | None) -> tuple[float, float]:
    if table is None:
        return (0.0, 0.0)
    wind = (table.number("east_m_s", WIND_M_S, 0.0), table.number("north_m_s", WIND_M_S, 0.0))
    table.finish()
    return wind


def _parse_coverage_map(table: ConfigTable) -> CoverageMap | None:
    """The layer's `coverage_map`, a path relative to the clouds file; None when absent."""
    if not table.has("coverage_map"):
        return None
    name = table.text("coverage_map")
    path = Path(name) if Path(name).is_absolute() else table.path.parent / name
    try:
        values = read_coverage_map(path)
    except InputError as error:
        raise table.error("coverage_map", name, f"{error} (the path is relative to the "
                          "clouds file; docs/clouds.md, 'Whole-planet clouds')") from None
    return CoverageMap(values, str(path))


def _parse_profile(table: ConfigTable) -> tuple[tuple[float, float], ...]:
    """(height fraction, factor) nodes, fractions increasing from 0 to 1; default flat."""
    table.asked.add("profile")
    if "profile" not in table.data:
        return ((0.0, 1.0), (1.0, 1.0))
    value = table.data.pop("profile")
    allowed = (f"a list of 2 to {MAX_PROFILE_NODES} [height fraction, factor] pairs, fractions "
               "increasing from 0 to 1, factors 0-1")
    try:
        nodes = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise table.error("profile", value, allowed) from None
    if (nodes.ndim != 2 or nodes.shape[1] != 2 or not 2 <= nodes.shape[0] <= MAX_PROFILE_NODES
            or not np.all(np.isfinite(nodes)) or nodes[0, 0] != 0.0 or nodes[-1, 0] != 1.0
            or np.any(np.diff(nodes[:, 0]) <= 0.0) or np.any(nodes[:, 1] < 0.0)
            or np.any(nodes[:, 1] > 1.0)):
        raise table.error("profile", value, allowed)
    return tuple((float(h), float(f)) for h, f in nodes)


def _parse_shape(table: ConfigTable | None) -> CloudShape:
    if table is None:
        return CloudShape()
    default = CloudShape()
    shape = CloudShape(
        seed=table.integer("seed", default.seed, low=0, high=2**32 - 1),
        scale_m=table.number("scale_m", NOISE_SCALE_M, default.scale_m),
        detail_scale_m=table.number("detail_scale_m", NOISE_SCALE_M, default.detail_scale_m),
        detail_strength=table.number("detail_strength", FRACTION, default.detail_strength),
        edge=table.number("edge", EDGE, default.edge),
        coverage_variation=table.number("coverage_variation", FRACTION,
                                        default.coverage_variation),
        stretch=table.number("stretch", STRETCH, default.stretch))
    table.finish()
    return shape


def _parse_particles(table: ConfigTable | None) -> CloudParticles:
    if table is None:
        return CloudParticles()
    phase = table.text("phase", "liquid", PHASES)
    if phase == "liquid":
        particles = CloudParticles(phase, table.number("effective_radius_um", LIQUID_RADIUS_UM),
                                   table.number("effective_variance", EFFECTIVE_VARIANCE, 0.1))
    else:
        particles = CloudParticles(phase, table.number("effective_radius_um", ICE_RADIUS_UM))
    table.finish()
    return particles
