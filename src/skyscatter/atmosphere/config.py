"""Read an atmosphere from a TOML file or a named preset; docs/config.md documents the schema.

Every value is checked before any work: a file that is not UTF-8 TOML (`config_file`), an
unknown key, a wrong type, a value outside its physical range (`config_ranges`), a list longer
than its cost allows, and an atmosphere whose optics come out infinite, NaN or thicker than
`config_ranges.OPTICAL_DEPTH` raise `ConfigError` naming the file, the key, the value and what
is allowed.
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import io
import math
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skyscatter.atmosphere import config_ranges as ranges
from skyscatter.atmosphere.config_file import preset_or_file, read_toml, read_utf8
from skyscatter.atmosphere.config_table import ConfigTable
from skyscatter.atmosphere.gas import (
    GasLayer,
    number_density_from_mass_density,
    number_density_from_pressure,
    surface_gravity,
)
from skyscatter.atmosphere.model import (
    DEFAULT_SCATTERING_ORDERS,
    MAX_PROFILE_LEVELS,
    MAX_SCATTERING_ORDERS,
    Atmosphere,
    Constituent,
    Planet,
)
from skyscatter.atmosphere.particle_config import parse_mie_optics
from skyscatter.atmosphere.profiles import (
    ExponentialProfile,
    LayeredProfile,
    ProfileLayer,
    ScaledProfile,
    TabulatedProfile,
    UniformLayerProfile,
    vertical_column,
)
from skyscatter.checks import shown
from skyscatter.errors import ConfigError, InputError
from skyscatter.optics.absorption import DOBSON_UNIT_M2, AbsorberOptics
from skyscatter.optics.aerosol import AngstromOptics
from skyscatter.optics.gases import GasMixture, GasSpecies, custom_species
from skyscatter.optics.phase import (
    CornetteShanksPhase,
    DoubleHenyeyGreensteinPhase,
    HenyeyGreensteinPhase,
    PenndorfPhase,
    RayleighPhase,
)
from skyscatter.optics.rayleigh import RayleighOptics, TabulatedScatteringOptics
from skyscatter.spectrum.star import AU_M, Star
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = ["MAX_SCATTERING_ORDERS", "PRESETS_DIR", "AtmosphereOutline", "list_presets",
           "load_atmosphere", "outline_atmosphere", "parse_atmosphere"]

PRESETS_DIR = Path(__file__).parent / "presets"


def list_presets() -> dict[str, str]:
    """Preset name -> one-line description, sorted by name."""
    result = {}
    for path in sorted(PRESETS_DIR.glob("*.toml")):
        result[path.stem] = str(read_toml(path).get("description", ""))
    return result


def load_atmosphere(name_or_path: str | Path) -> Atmosphere:
    """Load a preset by name (`skyscatter presets` lists them) or a TOML file by path."""
    path = _config_path(name_or_path)
    return parse_atmosphere(read_toml(path), path)


class AtmosphereOutline(NamedTuple):
    """What an atmosphere config names, read without building its optics
    (`outline_atmosphere`)."""

    name: str
    description: str
    body: str  # "" without an ephemeris
    constituents: tuple[str, ...]
    mean_ground_albedo: float
    radius_m: float
    top_altitude_m: float


def outline_atmosphere(name_or_path: str | Path) -> AtmosphereOutline:
    """The outline of a preset or TOML file: its names, planet and top, without the optics
    (the Mie tables of particles take seconds to a minute the first time): for listings.
    ConfigError for the parts it reads; the rest is checked by `load_atmosphere`."""
    path = _config_path(name_or_path)
    raw = read_toml(path)
    root = ConfigTable(dict(raw), path, "")
    radius, albedo, body, _ = _parse_planet(root.table("planet"))
    constituents = ["gas"] if root.table("gas", required=False) is not None else []
    items = raw.get("constituent", [])
    constituents += [str(item.get("name", "")) for item in
                     (items if isinstance(items, list) else []) if isinstance(item, dict)]
    return AtmosphereOutline(
        name=root.text("name", path.stem), description=root.text("description", ""),
        body=body, constituents=tuple(constituents),
        mean_ground_albedo=float(np.mean(albedo.values)), radius_m=radius,
        top_altitude_m=_parse_top(root.table("atmosphere")))


def _config_path(name_or_path: str | Path) -> Path:
    """The TOML file of a preset name or a path (`preset_or_file`)."""
    return preset_or_file(name_or_path, PRESETS_DIR, kind="preset", file_kind="config file",
                          keys=("preset", "config"),
                          listing="`skyscatter presets` lists them")


PLANET_BODIES = ("earth", "mars")  # [planet] body: bodies with an ephemeris (astro/)
KNOWN_TOP_LEVEL = ("name", "description", "sources", "planet", "star", "atmosphere",
                   "constituent", "tables", "gas")


def parse_atmosphere(raw: dict[str, Any], path: Path) -> Atmosphere:
    """Build an Atmosphere from a parsed TOML document (`path` is named in messages and is the
    base of relative data file paths)."""
    root = ConfigTable(dict(raw), path, "")
    name = root.text("name", path.stem)
    description = root.text("description", "")
    root.data.pop("sources", None)  # free-form citations, for people
    radius, albedo, body, planet_mass = _parse_planet(root.table("planet"))
    star = _parse_star(root.table("star"))
    top = _parse_top(root.table("atmosphere"))
    orders = DEFAULT_SCATTERING_ORDERS
    tables_table = root.table("tables", required=False)
    if tables_table is not None:
        orders = tables_table.integer("orders", DEFAULT_SCATTERING_ORDERS, low=1,
                                      high=MAX_SCATTERING_ORDERS)
        tables_table.finish()
    constituents_raw = root.data.pop("constituent", None)
    constituents, constituents_raw = _parse_gas(root, radius, planet_mass, constituents_raw)
    if not isinstance(constituents_raw, list) or not (constituents_raw or constituents):
        raise ConfigError("[[constituent]] is missing: an atmosphere needs at least one (or a "
                          "[gas] table)", path=path, key="constituent")
    if len(constituents_raw) + len(constituents) > ranges.MAX_CONSTITUENTS:
        raise ConfigError(f"{len(constituents_raw) + len(constituents)} constituents, more than "
                          f"{ranges.MAX_CONSTITUENTS}: each scattering constituent adds "
                          "84 MB to the scattering table at 16 wavelengths and time to every "
                          "precomputation (20 000 would need 1.7 TB and days); merge "
                          "constituents that share a profile", path=path, key="constituent",
                          value=len(constituents_raw) + len(constituents),
                          allowed=f"<= {ranges.MAX_CONSTITUENTS} constituents")
    keys = ["gas"] * len(constituents)  # the config key of each constituent, for messages
    for index, item in enumerate(constituents_raw):
        keys.append(f"constituent[{index}]")
        if not isinstance(item, dict):
            raise ConfigError(f"constituent[{index}] = {shown(item)} is not allowed: a table",
                              path=path, key=f"constituent[{index}]", value=item)
        constituents.append(_parse_constituent(ConfigTable(dict(item), path,
                                                      f"constituent[{index}]"), top))
    names = [c.name for c in constituents]
    if len(set(names)) != len(names):
        raise ConfigError(f"constituent names must be unique, got {shown(names)}", path=path,
                          key="constituent.name")
    if root.data:
        key = next(iter(root.data))
        close = difflib.get_close_matches(key, KNOWN_TOP_LEVEL, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ConfigError(f"unknown key {shown(key)}{hint}", path=path, key=key)
    planet = Planet(name=name, radius_m=radius, ground_albedo=albedo, star=star, body=body)
    atmosphere = Atmosphere(planet=planet, top_altitude_m=top, constituents=tuple(constituents),
                            name=name, description=description, source=str(path),
                            scattering_orders=orders)
    _check_optics(atmosphere, path, keys)
    return atmosphere


def _parse_planet(table: ConfigTable) -> tuple[float, SpectralParameter, str, float | None]:
    """(radius [m], ground albedo, ephemeris body, mass [kg] or None) of the [planet] table."""
    radius = table.number("radius_m", ranges.PLANET_RADIUS_M)
    albedo = table.spectral("ground_albedo", ranges.FRACTION, 0.1)
    body = table.text("body", "", choices=PLANET_BODIES)
    planet_mass = (table.number("mass_kg", ranges.PLANET_MASS_KG)
                   if table.has("mass_kg") else None)  # for [gas]: g = G M / R^2
    table.finish()
    return radius, albedo, body, planet_mass


def _parse_top(table: ConfigTable) -> float:
    """The top altitude [m] of the [atmosphere] table."""
    top = table.number("top_altitude_m", ranges.TOP_ALTITUDE_M)
    table.finish()
    return top


# [gas]: exactly one of these gives the surface density.
GAS_SURFACE_KEYS = {"surface_pressure_pa": ranges.SURFACE_PRESSURE_PA,
                    "surface_density_kg_m3": ranges.SURFACE_DENSITY_KG_M3,
                    "surface_number_density_m3": ranges.SURFACE_NUMBER_DENSITY_M3}


def _parse_gas(root: ConfigTable, radius_m: float, planet_mass_kg: float | None,
               constituents_raw: Any) -> tuple[list[Constituent], Any]:
    """The [gas] table -> ([the "gas" constituent] or [], the [[constituent]] list with each
    `density = { type = "gas", mole_fraction = x }` replaced by x times the gas's exponential
    profile). atmosphere/gas.py has the physics, docs/config.md the schema."""
    table = root.table("gas", required=False)
    layer = None if table is None else _parse_gas_layer(table, radius_m, planet_mass_kg)
    if not isinstance(constituents_raw, list):
        return ([] if layer is None else [layer.constituent("gas")],
                [] if constituents_raw is None and layer is not None else constituents_raw)
    rewritten = []
    for index, item in enumerate(constituents_raw):
        density = item.get("density") if isinstance(item, dict) else None
        if isinstance(density, dict) and density.get("type") == "gas":
            sub = ConfigTable(dict(density), root.path, f"constituent[{index}].density")
            if layer is None:
                raise sub.error("type", "gas", "a [gas] table, whose number density a 'gas' "
                                "density follows")
            sub.text("type")
            fraction = sub.number("mole_fraction", ranges.FRACTION)
            sub.finish()
            item = dict(item, density={"type": "exponential",
                                       "scale_height_m": layer.scale_height_m,
                                       "surface_density": fraction
                                       * layer.surface_number_density_m3})
        rewritten.append(item)
    return ([] if layer is None else [layer.constituent("gas")]), rewritten


def _parse_gas_layer(table: ConfigTable, radius_m: float, planet_mass_kg: float | None) -> GasLayer:
    temperature = table.number("surface_temperature_k", ranges.SURFACE_TEMPERATURE_K)
    given = [key for key in GAS_SURFACE_KEYS if table.has(key)]
    if len(given) != 1:
        raise ConfigError(f"[gas] needs exactly one of {', '.join(GAS_SURFACE_KEYS)}"
                          + (f"; got {', '.join(given)}" if given else ""), path=table.path,
                          key=f"gas.{given[-1] if given else next(iter(GAS_SURFACE_KEYS))}",
                          allowed=" or ".join(GAS_SURFACE_KEYS))
    surface = table.number(given[0], GAS_SURFACE_KEYS[given[0]])
    if table.has("gravity_m_s2") and planet_mass_kg is not None:
        raise table.error("gravity_m_s2", table.data["gravity_m_s2"],
                          "give gas.gravity_m_s2 or planet.mass_kg, not both")
    if table.has("gravity_m_s2"):
        gravity = table.number("gravity_m_s2", ranges.GRAVITY_M_S2)
    elif planet_mass_kg is not None:
        gravity = surface_gravity(planet_mass_kg, radius_m)
        if not ranges.GRAVITY_M_S2.low <= gravity <= ranges.GRAVITY_M_S2.high:
            raise ConfigError(
                f"planet.mass_kg = {planet_mass_kg:g} with radius_m = {radius_m:g} gives a "
                f"surface gravity g = G M / R^2 = {gravity:.3g} m s^-2; allowed: "
                f"{ranges.GRAVITY_M_S2.allowed} m s^-2 (a 1 km asteroid to a brown dwarf)",
                path=table.path, key="planet.mass_kg", value=planet_mass_kg,
                allowed=ranges.GRAVITY_M_S2.allowed)
    else:
        raise ConfigError("gas.gravity_m_s2 is missing: give it, or planet.mass_kg (then "
                          "g = G M / R^2)", path=table.path, key="gas.gravity_m_s2")
    normalize = table.flag("normalize", False)
    phase = table.text("phase", "rayleigh", ("rayleigh", "penndorf"))
    custom = _parse_gas_species(table)
    composition_table = table.table("composition")
    if len(composition_table.data) > ranges.MAX_GASES:
        raise table.error("composition", f"{len(composition_table.data)} gases",
                          f"at most {ranges.MAX_GASES} gases")
    fractions = {key: composition_table.number(key, ranges.FRACTION)
                 for key in list(composition_table.data)}
    if not fractions:
        raise table.error("composition", {}, "at least one gas: { n2 = 0.78, o2 = 0.21, ... }")
    try:
        mixture = GasMixture.from_composition(fractions, custom, normalize=normalize,
                                              phase=phase)
    except InputError as error:
        key = "gas.composition" + ("" if error.key == "composition" else f".{error.key}")
        raise ConfigError(f"{key}: {error}", path=table.path, key=key, value=error.value,
                          allowed=error.allowed) from None
    table.finish()
    if given[0] == "surface_pressure_pa":
        density = number_density_from_pressure(surface, temperature)
    elif given[0] == "surface_density_kg_m3":
        density = number_density_from_mass_density(surface, mixture.molar_mass_kg_mol)
    else:
        density = surface
    return GasLayer(mixture, temperature, density, gravity)


def _parse_gas_species(table: ConfigTable) -> list[GasSpecies]:
    """[[gas.species]]: gases beyond the built-in ones, from their molar mass and refractivity
    or polarisability."""
    result = []
    for sub in table.tables("species", ranges.MAX_GASES, "more gases than any published "
                            "composition lists"):
        name = sub.text("name")
        molar_mass = sub.number("molar_mass_g_mol", ranges.MOLAR_MASS_G_MOL)
        refractivity = (sub.spectral("refractivity", ranges.REFRACTIVITY)
                        if sub.has("refractivity") else None)
        number_density = (sub.number("refractivity_number_density_m3",
                                     ranges.REFRACTIVITY_NUMBER_DENSITY_M3)
                          if sub.has("refractivity_number_density_m3") else None)
        polarizability = (sub.number("polarizability_m3", ranges.POLARIZABILITY_M3)
                          if sub.has("polarizability_m3") else None)
        depolarization = sub.number("depolarization", ranges.DEPOLARIZATION, 0.0)
        sub.finish()
        if any(gas.name == name.strip().lower() for gas in result):
            raise sub.error("name", name, "a name not used by another [[gas.species]]")
        try:
            result.append(custom_species(
                name, molar_mass, refractivity=refractivity,
                refractivity_number_density_m3=number_density,
                polarizability_m3=polarizability, depolarization=depolarization))
        except InputError as error:
            raise sub.wrap(error) from None
    return result


def _parse_star(table: ConfigTable) -> Star:
    kind = table.text("type", "sun", ("sun", "blackbody"))
    if table.has("distance_au") and table.has("distance_m"):
        raise table.error("distance_m", table.data["distance_m"],
                          "give distance_au or distance_m, not both")
    if table.has("distance_m"):
        distance = table.number("distance_m", ranges.STAR_DISTANCE_M)
    else:
        distance = table.number("distance_au", ranges.STAR_DISTANCE_AU, 1.0) * AU_M
    limb = table.flag("limb_darkening", True)
    try:
        if kind == "sun":
            star = Star.sun(distance / AU_M)
        else:
            star = Star.blackbody(table.text("name", "star"),
                                  table.number("temperature_k", ranges.STAR_TEMPERATURE_K),
                                  table.number("radius_m", ranges.STAR_RADIUS_M), distance)
    except InputError as error:
        raise ConfigError(f"[{table.prefix}] {error}", path=table.path,
                          key=f"{table.prefix}.{error.key}", value=error.value,
                          allowed=error.allowed) from None
    table.finish()
    return dataclasses.replace(star, limb_darkening=limb)


def _parse_constituent(table: ConfigTable, top_m: float) -> Constituent:
    name = table.text("name")
    profile = _parse_profile(table.table("density"), top_m)
    optics_table = table.table("optics")
    kind = optics_table.text("type", choices=("rayleigh", "absorber", "angstrom", "coefficients",
                                              "mie"))
    # A layer's column is known exactly (and kept on any altitude levels); others are sampled.
    exact = isinstance(profile, UniformLayerProfile)
    column = profile.column if exact else vertical_column(profile, top_m)
    target_column = column if exact and column > 0.0 else None
    zero = f"a density profile that is not zero everywhere ({table.prefix}.density is)"
    if kind == "absorber" and table.has("column_dobson"):
        if column <= 0.0:
            raise table.error("column_dobson", table.data["column_dobson"], zero)
        target_column = table.number("column_dobson", ranges.COLUMN_DOBSON) * DOBSON_UNIT_M2
    if kind in ("angstrom", "mie") and optics_table.has("optical_depth") and column <= 0.0:
        raise optics_table.error("optical_depth", optics_table.data["optical_depth"], zero)
    if kind == "angstrom" and optics_table.has("optical_depth"):
        target_column = 1.0  # unit column: extinction per density = optical depth
    if kind == "mie":
        optics, mie_column = _parse_particles(optics_table)
        target_column = target_column if mie_column is None else mie_column
    else:
        optics = _parse_optics(kind, optics_table)
    table.finish()
    return Constituent(name=name, profile=profile, optics=optics, vertical_column=target_column)


def _parse_particles(table: ConfigTable) -> tuple[object, float | None]:
    """`type = "mie"` optics (atmosphere/particle_config.py) and their vertical column."""
    try:
        result = parse_mie_optics(table, _parse_phase(table.table("blend", required=False)))
    except InputError as error:
        raise table.wrap(error) from None
    table.finish()
    return result


def _parse_profile(table: ConfigTable, top_m: float) -> object:
    kind = table.text("type", choices=("exponential", "layers", "table", "layer"))
    if kind == "layer":
        profile = _parse_uniform_layer(table, top_m)
    elif kind == "exponential":
        profile = ExponentialProfile(table.number("scale_height_m", ranges.SCALE_HEIGHT_M),
                                     table.number("surface_density", ranges.DENSITY, 1.0))
    elif kind == "layers":
        layers = [_parse_layer(layer, top_m) for layer in table.tables(
            "layers", ranges.MAX_LAYERS, 'a profile with more layers is a table: type = "table"')]
        if not layers:
            raise table.error("layers", table.data.get("layers"),
                              "a non-empty list of layer tables")
        profile = ScaledProfile(LayeredProfile(tuple(layers)),
                                table.number("peak_density", ranges.DENSITY, 1.0))
    else:
        altitudes, values = _profile_table(table)
        interpolation = table.text("interpolation", "log", ("log", "linear"))
        profile = TabulatedProfile(tuple(altitudes), tuple(values), interpolation)
    table.finish()
    return profile


def _parse_uniform_layer(table: ConfigTable, top_m: float) -> UniformLayerProfile:
    """`type = "layer"`: uniform between base and top, inside the atmosphere, with edges no
    wider than the layer (and, above the ground, no lower edge below it)."""
    base = table.number("base_altitude_m", ranges.LAYER_ALTITUDE_M)
    top = table.number("top_altitude_m", ranges.LAYER_ALTITUDE_M)
    if top <= base:
        raise table.error("top_altitude_m", top, f"above base_altitude_m = {base:g} m")
    if top > top_m:
        raise table.error("top_altitude_m", top, f"<= the top of the atmosphere, "
                          f"atmosphere.top_altitude_m = {top_m:g} m")
    thinnest = 2.0 * top_m / (MAX_PROFILE_LEVELS - 1)  # two spacings of the finest levels
    if top - base < thinnest:
        raise table.error("top_altitude_m", top, f">= base_altitude_m + {thinnest:.3g} m: the "
                          f"solvers sample at most {MAX_PROFILE_LEVELS} levels over "
                          f"{top_m:g} m, and a thinner layer falls between them")
    edge = table.number("edge_m", ranges.LAYER_EDGE_M, 0.0)
    if edge > top - base:
        raise table.error("edge_m", edge, f"<= the layer's thickness, top_altitude_m - "
                          f"base_altitude_m = {top - base:g} m")
    if base > 0.0 and edge / 2.0 > base or top + edge / 2.0 > top_m:
        raise table.error("edge_m", edge, "an edge that stays inside the atmosphere: edge_m / 2 "
                          f"<= base_altitude_m = {base:g} m (or a base on the ground) and "
                          f"top_altitude_m + edge_m / 2 <= {top_m:g} m")
    return UniformLayerProfile(base, top, table.number("peak_density", ranges.DENSITY, 1.0),
                               edge)


def _parse_layer(layer: ConfigTable, top_m: float) -> ProfileLayer:
    """One of Bruneton's layers; its exponential stays finite up to the top of the atmosphere."""
    rate = layer.number("exp_scale_per_m", ranges.LAYER_RATE_PER_M, 0.0)
    if rate * top_m > ranges.MAX_EXPONENT:
        raise layer.error("exp_scale_per_m", rate,
                          f"<= {ranges.MAX_EXPONENT / top_m:.3g} m^-1 in an atmosphere "
                          f"{top_m:g} m high (e^(exp_scale_per_m x top_altitude_m) must stay "
                          f"below e^{ranges.MAX_EXPONENT:g}, near the largest float64)")
    result = ProfileLayer(
        top_altitude_m=layer.number("top_altitude_m", ranges.ALTITUDE_M, math.inf),
        exp_term=layer.number("exp_term", ranges.LAYER_TERM, 0.0),
        exp_scale_per_m=rate,
        linear_per_m=layer.number("linear_per_m", ranges.LAYER_RATE_PER_M, 0.0),
        constant=layer.number("constant", ranges.LAYER_TERM, 0.0))
    layer.finish()
    return result


# A density CSV file: 100 000 rows (`config_ranges.MAX_LIST_LENGTH`) of two numbers with full
# precision are ~4 MB; 16 MiB leaves room for comments and more columns.
MAX_CSV_BYTES = 16 * 2**20


def _profile_table(table: ConfigTable) -> tuple[np.ndarray, np.ndarray]:
    """Altitude [m] and density columns, inline or from a CSV next to the config."""
    if table.has("file"):
        altitudes, values = _read_profile_csv(table)
        for key, column, bounds in (("altitude_m", altitudes, ranges.ALTITUDE_M),
                                    ("value", values, ranges.DENSITY)):
            inside = np.isfinite(column) & (column >= bounds.low) & (column <= bounds.high)
            if not np.all(inside):
                raise table.error(key, column.tolist(), f"every {key} {bounds.allowed}; "
                                  f"{float(column[np.argmin(inside)])!r} is not")
    else:
        altitudes = table.numbers("altitude_m", ranges.ALTITUDE_M)
        values = table.numbers("value", ranges.DENSITY)
    if (altitudes.size != values.size or altitudes.size < 2
            or not np.all(np.diff(altitudes) > 0)):
        raise table.error("altitude_m", altitudes.tolist(),
                          "at least 2 strictly increasing altitudes, one value each")
    return altitudes, values


def _read_profile_csv(table: ConfigTable) -> tuple[np.ndarray, np.ndarray]:
    """The altitude and density columns of the CSV file `file` names (docs/config.md)."""
    name = table.text("file")
    csv_path = (table.path.parent / name).resolve()
    allowed = (f"a readable UTF-8 CSV file of at most {MAX_CSV_BYTES // 2**20} MiB and "
               f"{ranges.MAX_LIST_LENGTH} rows")
    try:
        text = read_utf8(csv_path, MAX_CSV_BYTES)
    except OSError as error:
        raise table.error("file", name, f"{allowed} ({error.strerror})") from None
    except ValueError as error:
        raise table.error("file", name, f"{allowed} (it {error})") from None
    try:
        rows = [row for row in csv.reader(io.StringIO(text, newline=""))
                if row and not row[0].lstrip().startswith("#")]
        if len(rows) > ranges.MAX_LIST_LENGTH + 1:
            raise table.error("file", name, f"{allowed} (it has {len(rows) - 1} rows)")
        header = [column_name.strip() for column_name in rows[0]]
        altitude_column = header.index("altitude_m")
        if len(header) == 2 and not table.has("column"):
            density_column = 1 - altitude_column
        else:
            column = table.text("column", "number_density_m3")
            if column not in header:
                raise table.error("column", column, f"a column of {name}: "
                                  + ", ".join(h for h in header if h != "altitude_m"))
            density_column = header.index(column)
        altitudes = np.array([float(r[altitude_column]) for r in rows[1:]])
        values = np.array([float(r[density_column]) for r in rows[1:]])
    except (ValueError, IndexError, csv.Error):
        raise table.error("file", name, "a CSV with a header 'altitude_m,<density column>' "
                          "and numeric rows") from None
    return altitudes, values


def _parse_phase(table: ConfigTable | None, default: str | None = None) -> object:
    if table is None:
        if default is None:
            return None
        return {"rayleigh": RayleighPhase, "penndorf": PenndorfPhase}[default]()
    kind = table.text("type", choices=("rayleigh", "penndorf", "henyey-greenstein",
                                       "double-henyey-greenstein", "cornette-shanks"))
    if kind == "rayleigh":
        phase = RayleighPhase()
    elif kind == "penndorf":
        phase = PenndorfPhase()
    elif kind == "henyey-greenstein":
        phase = HenyeyGreensteinPhase(table.spectral("g", ranges.ASYMMETRY))
    elif kind == "cornette-shanks":
        phase = CornetteShanksPhase(table.spectral("g", ranges.ASYMMETRY))
    else:
        phase = DoubleHenyeyGreensteinPhase(table.spectral("g1", ranges.ASYMMETRY),
                                            table.spectral("g2", ranges.ASYMMETRY),
                                            table.spectral("alpha", ranges.FRACTION))
    table.finish()
    return phase


def _parse_optics(kind: str, table: ConfigTable) -> object:
    try:
        if kind == "rayleigh":
            depolarization = (table.number("depolarization", ranges.DEPOLARIZATION)
                              if table.has("depolarization") else None)
            optics = RayleighOptics(
                gas=table.text("gas", "air"),
                king=table.text("king_factor", "bodhaine-1999"),
                depolarization=depolarization,
                co2_ppm=table.number("co2_ppm", ranges.CO2_PPM, 360.0),
                phase=table.text("phase", "rayleigh", ("rayleigh", "penndorf")))
        elif kind == "absorber":
            if table.has("cross_section") and isinstance(table.data["cross_section"], str):
                cross_section = table.text("cross_section")
            else:
                cross_section = table.spectral("cross_section",
                                               ranges.ABSORPTION_CROSS_SECTION_M2)
            optics = AbsorberOptics(cross_section)
        elif kind == "angstrom":
            if table.has("optical_depth") == table.has("extinction_per_m"):
                raise ConfigError(f"{table.prefix}: give exactly one of optical_depth "
                                  "(vertical, at the reference wavelength) or extinction_per_m "
                                  "(at density 1)", path=table.path,
                                  key=f"{table.prefix}.optical_depth")
            extinction = (table.number("optical_depth", ranges.OPTICAL_DEPTH)
                          if table.has("optical_depth")
                          else table.number("extinction_per_m", ranges.EXTINCTION_PER_M))
            optics = AngstromOptics(
                extinction_at_reference=extinction,
                reference_wavelength_nm=table.number("reference_wavelength_nm",
                                                     ranges.WAVELENGTH_NM, 550.0),
                angstrom_exponent=table.number("angstrom_exponent", ranges.ANGSTROM_EXPONENT,
                                               0.0),
                single_scattering_albedo=table.spectral("single_scattering_albedo",
                                                        ranges.FRACTION, 1.0),
                phase=_parse_phase(table.table("phase")))
        else:
            scattering = table.spectral("scattering_per_m", ranges.EXTINCTION_PER_M)
            extinction = (table.spectral("extinction_per_m", ranges.EXTINCTION_PER_M)
                          if table.has("extinction_per_m") else None)
            optics = TabulatedScatteringOptics(
                scattering, extinction, _parse_phase(table.table("phase")))
    except InputError as error:
        raise table.wrap(error) from None
    table.finish()
    return optics


def _check_optics(atmosphere: Atmosphere, path: Path, keys: list[str]) -> None:
    """ConfigError naming the constituent (its config key in `keys`) whose optics are not
    finite, or whose vertical optical depth exceeds `config_ranges.OPTICAL_DEPTH`, anywhere in
    skyscatter's spectral range (`config_ranges.CHECK_WAVELENGTHS_NM`): values each within its
    own range can still multiply into one (a density of 1e30 m^-3 times a cross-section)."""
    wavelengths = ranges.CHECK_WAVELENGTHS_NM
    with np.errstate(all="ignore"):
        profile = atmosphere.optical_profile(wavelengths)
        depth = np.trapezoid(profile.density, profile.altitudes_m, axis=1)[:, None] * (
            profile.extinction_per_density)
    for key, name, row, scattering in zip(keys, profile.names, depth,
                                          profile.scattering_per_density, strict=True):
        finite = np.isfinite(row) & np.isfinite(scattering)
        if not np.all(finite) or np.any(row > ranges.OPTICAL_DEPTH.high):
            index = int(np.argmin(finite)) if not np.all(finite) else int(np.argmax(row))
            raise ConfigError(
                f"{key} ({shown(name)}): vertical optical depth {row[index]:.3g} at "
                f"{wavelengths[index]:g} nm; allowed: {ranges.OPTICAL_DEPTH.allowed} over "
                f"{wavelengths[0]:g}-{wavelengths[-1]:g} nm (thicker, no light gets through "
                "within the scattering orders the tables may iterate); check the density and "
                "the optics of this constituent", path=path, key=key, value=float(row[index]),
                allowed=ranges.OPTICAL_DEPTH.allowed)
