"""Read an atmosphere from a TOML file or a named preset; docs/config.md documents the schema.

Every value is checked: an unknown key, a wrong type or an out-of-range value raises
`ConfigError` naming the file, the key, the value and what is allowed.
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.atmosphere.config_table import ConfigTable
from skyscatter.atmosphere.gas import (
    GasLayer,
    number_density_from_mass_density,
    number_density_from_pressure,
    surface_gravity,
)
from skyscatter.atmosphere.model import (
    DEFAULT_SCATTERING_ORDERS,
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
    vertical_column,
)
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

__all__ = ["PRESETS_DIR", "list_presets", "load_atmosphere", "parse_atmosphere"]

PRESETS_DIR = Path(__file__).parent / "presets"


def list_presets() -> dict[str, str]:
    """Preset name -> one-line description, sorted by name."""
    result = {}
    for path in sorted(PRESETS_DIR.glob("*.toml")):
        with path.open("rb") as handle:
            result[path.stem] = str(tomllib.load(handle).get("description", ""))
    return result


def load_atmosphere(name_or_path: str | Path) -> Atmosphere:
    """Load a preset by name (`skyscatter presets` lists them) or a TOML file by path."""
    text = str(name_or_path)
    path = Path(text)
    if not path.suffix and not path.exists():
        path = PRESETS_DIR / f"{text}.toml"
        if not path.exists():
            names = sorted(p.stem for p in PRESETS_DIR.glob("*.toml"))
            close = difflib.get_close_matches(text, names, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise InputError(f"unknown preset '{text}'{hint} (`skyscatter presets` lists them; "
                             "or give the path of a .toml file)", key="preset", value=text,
                             allowed=", ".join(names))
    if not path.is_file():
        raise InputError(f"config file '{path}' does not exist", key="config", value=text)
    try:
        with path.open("rb") as handle:
            raw = tomllib.load(handle)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"not valid TOML: {error}", path=path) from None
    except OSError as error:
        raise ConfigError(f"cannot read: {error.strerror}", path=path) from None
    return parse_atmosphere(raw, path)


PLANET_BODIES = ("earth", "mars")  # [planet] body: bodies with an ephemeris (astro/)
KNOWN_TOP_LEVEL = ("name", "description", "sources", "planet", "star", "atmosphere",
                   "constituent", "tables", "gas")
# Bounds of [tables] orders: 1 is single scattering only; past 1000 a typo is likelier than a
# need (each order costs about as much as the single-scattering table; docs/physics/orders.md).
MAX_SCATTERING_ORDERS = 1000


def parse_atmosphere(raw: dict[str, Any], path: Path) -> Atmosphere:
    """Build an Atmosphere from a parsed TOML document (`path` is named in messages and is the
    base of relative data file paths)."""
    root = ConfigTable(dict(raw), path, "")
    name = root.text("name", path.stem)
    description = root.text("description", "")
    root.data.pop("sources", None)  # free-form citations, for people
    planet_table = root.table("planet")
    radius = planet_table.number("radius_m", low=1.0, low_open=True)
    albedo = planet_table.spectral("ground_albedo", 0.1, low=0.0, high=1.0)
    body = planet_table.text("body", "", choices=PLANET_BODIES)
    planet_mass = (planet_table.number("mass_kg", low=0.0, low_open=True)
                   if planet_table.has("mass_kg") else None)  # for [gas]: g = G M / R^2
    planet_table.finish()
    star = _parse_star(root.table("star"))
    atmosphere_table = root.table("atmosphere")
    top = atmosphere_table.number("top_altitude_m", low=0.0, low_open=True)
    atmosphere_table.finish()
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
    for index, item in enumerate(constituents_raw):
        if not isinstance(item, dict):
            raise ConfigError(f"constituent[{index}] must be a table", path=path,
                              key=f"constituent[{index}]")
        constituents.append(_parse_constituent(ConfigTable(dict(item), path,
                                                      f"constituent[{index}]"), top))
    names = [c.name for c in constituents]
    if len(set(names)) != len(names):
        raise ConfigError(f"constituent names must be unique, got {names}", path=path,
                          key="constituent.name")
    if root.data:
        key = next(iter(root.data))
        close = difflib.get_close_matches(key, KNOWN_TOP_LEVEL, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ConfigError(f"unknown key {key!r}{hint}", path=path, key=key)
    planet = Planet(name=name, radius_m=radius, ground_albedo=albedo, star=star, body=body)
    return Atmosphere(planet=planet, top_altitude_m=top, constituents=tuple(constituents),
                      name=name, description=description, source=str(path),
                      scattering_orders=orders)


# [gas]: exactly one of these gives the surface density.
GAS_SURFACE_KEYS = ("surface_pressure_pa", "surface_density_kg_m3", "surface_number_density_m3")


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
            fraction = sub.number("mole_fraction", low=0.0, high=1.0)
            sub.finish()
            item = dict(item, density={"type": "exponential",
                                       "scale_height_m": layer.scale_height_m,
                                       "surface_density": fraction
                                       * layer.surface_number_density_m3})
        rewritten.append(item)
    return ([] if layer is None else [layer.constituent("gas")]), rewritten


def _parse_gas_layer(table: ConfigTable, radius_m: float, planet_mass_kg: float | None) -> GasLayer:
    temperature = table.number("surface_temperature_k", low=0.0, low_open=True)
    given = [key for key in GAS_SURFACE_KEYS if table.has(key)]
    if len(given) != 1:
        raise ConfigError(f"[gas] needs exactly one of {', '.join(GAS_SURFACE_KEYS)}"
                          + (f"; got {', '.join(given)}" if given else ""), path=table.path,
                          key=f"gas.{given[-1] if given else GAS_SURFACE_KEYS[0]}",
                          allowed=" or ".join(GAS_SURFACE_KEYS))
    surface = table.number(given[0], low=0.0, low_open=True)
    if table.has("gravity_m_s2") and planet_mass_kg is not None:
        raise table.error("gravity_m_s2", table.data["gravity_m_s2"],
                          "give gas.gravity_m_s2 or planet.mass_kg, not both")
    if table.has("gravity_m_s2"):
        gravity = table.number("gravity_m_s2", low=0.0, low_open=True)
    elif planet_mass_kg is not None:
        gravity = surface_gravity(planet_mass_kg, radius_m)
    else:
        raise ConfigError("gas.gravity_m_s2 is missing: give it, or planet.mass_kg (then "
                          "g = G M / R^2)", path=table.path, key="gas.gravity_m_s2")
    normalize = table.flag("normalize", False)
    phase = table.text("phase", "rayleigh", ("rayleigh", "penndorf"))
    custom = _parse_gas_species(table)
    composition_table = table.table("composition")
    fractions = {key: composition_table.number(key, low=0.0, high=1.0)
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
    table.asked.add("species")
    items = table.data.pop("species", [])
    if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
        raise table.error("species", items, "an array of tables [[gas.species]]")
    result = []
    for index, item in enumerate(items):
        sub = ConfigTable(dict(item), table.path, f"gas.species[{index}]")
        name = sub.text("name")
        molar_mass = sub.number("molar_mass_g_mol", low=0.0, low_open=True)
        refractivity = sub.spectral("refractivity", low=0.0) if sub.has("refractivity") else None
        number_density = (sub.number("refractivity_number_density_m3", low=0.0, low_open=True)
                          if sub.has("refractivity_number_density_m3") else None)
        polarizability = (sub.number("polarizability_m3", low=0.0, low_open=True)
                          if sub.has("polarizability_m3") else None)
        depolarization = sub.number("depolarization", 0.0, low=0.0, high=0.5)
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
        distance = table.number("distance_m", low=0.0, low_open=True)
    else:
        distance = table.number("distance_au", 1.0, low=0.0, low_open=True) * AU_M
    limb = table.flag("limb_darkening", True)
    try:
        if kind == "sun":
            star = Star.sun(distance / AU_M)
        else:
            star = Star.blackbody(table.text("name", "star"),
                                  table.number("temperature_k", low=0.0, low_open=True),
                                  table.number("radius_m", low=0.0, low_open=True), distance)
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
    target_column = None
    if kind == "absorber" and table.has("column_dobson"):
        if vertical_column(profile, top_m) <= 0.0:
            raise table.error("column_dobson", table.data["column_dobson"],
                              "the density profile is zero everywhere")
        target_column = table.number("column_dobson", low=0.0) * DOBSON_UNIT_M2
    if kind == "angstrom" and optics_table.has("optical_depth"):
        if vertical_column(profile, top_m) <= 0.0:
            raise optics_table.error("optical_depth", optics_table.data["optical_depth"],
                                     "the density profile is zero everywhere")
        target_column = 1.0  # unit column: extinction per density = optical depth
    if kind == "mie":
        if optics_table.has("optical_depth") and vertical_column(profile, top_m) <= 0.0:
            raise optics_table.error("optical_depth", optics_table.data["optical_depth"],
                                     "the density profile is zero everywhere")
        optics, target_column = _parse_particles(optics_table)
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
    kind = table.text("type", choices=("exponential", "layers", "table"))
    if kind == "exponential":
        profile = ExponentialProfile(table.number("scale_height_m", low=0.0, low_open=True),
                                     table.number("surface_density", 1.0, low=0.0))
    elif kind == "layers":
        layers_raw = table.data.pop("layers", None)
        if not isinstance(layers_raw, list) or not layers_raw:
            raise table.error("layers", layers_raw, "a non-empty list of layer tables")
        layers = []
        for index, item in enumerate(layers_raw):
            if not isinstance(item, dict):
                raise table.error(f"layers[{index}]", item, "a table")
            layer = ConfigTable(dict(item), table.path, f"{table.prefix}.layers[{index}]")
            layers.append(ProfileLayer(
                top_altitude_m=layer.number("top_altitude_m", math.inf),
                exp_term=layer.number("exp_term", 0.0),
                exp_scale_per_m=layer.number("exp_scale_per_m", 0.0),
                linear_per_m=layer.number("linear_per_m", 0.0),
                constant=layer.number("constant", 0.0)))
            layer.finish()
        profile = ScaledProfile(LayeredProfile(tuple(layers)),
                                table.number("peak_density", 1.0, low=0.0))
    else:
        altitudes, values = _profile_table(table)
        interpolation = table.text("interpolation", "log", ("log", "linear"))
        profile = TabulatedProfile(tuple(altitudes), tuple(values), interpolation)
    table.finish()
    return profile


def _profile_table(table: ConfigTable) -> tuple[np.ndarray, np.ndarray]:
    """Altitude [m] and density columns, inline or from a CSV next to the config."""
    if table.has("file"):
        name = table.text("file")
        csv_path = (table.path.parent / name).resolve()
        try:
            with csv_path.open(newline="") as handle:
                rows = [row for row in csv.reader(handle)
                        if row and not row[0].lstrip().startswith("#")]
            header, body = rows[0], rows[1:]
            header = [column_name.strip() for column_name in header]
            altitude_column = header.index("altitude_m")
            if len(header) == 2 and not table.has("column"):
                density_column = 1 - altitude_column
            else:
                column = table.text("column", "number_density_m3")
                if column not in header:
                    raise table.error("column", column, f"a column of {name}: "
                                      + ", ".join(h for h in header if h != "altitude_m"))
                density_column = header.index(column)
            altitudes = np.array([float(r[altitude_column]) for r in body])
            values = np.array([float(r[density_column]) for r in body])
        except OSError as error:
            raise table.error("file", name, f"a readable CSV file ({error.strerror})") from None
        except (ValueError, IndexError):
            raise table.error("file", name, "a CSV with a header 'altitude_m,<density column>' "
                              "and numeric rows") from None
    else:
        altitudes = table.numbers("altitude_m")
        values = table.numbers("value", low=0.0)
    if (altitudes.size != values.size or altitudes.size < 2
            or not np.all(np.isfinite(altitudes)) or not np.all(np.diff(altitudes) > 0)):
        raise table.error("altitude_m", altitudes.tolist(),
                          "at least 2 strictly increasing altitudes, one value each")
    if np.any(values < 0) or not np.all(np.isfinite(values)):
        raise table.error("value", values.tolist(), "finite densities >= 0")
    return altitudes, values


def _parse_phase(table: ConfigTable | None, default: str | None = None) -> object:
    if table is None:
        if default is None:
            return None
        return {"rayleigh": RayleighPhase, "penndorf": PenndorfPhase}[default]()
    kind = table.text("type", choices=("rayleigh", "penndorf", "henyey-greenstein",
                                       "double-henyey-greenstein", "cornette-shanks"))
    open_unit = {"low": -0.999999, "high": 0.999999}
    if kind == "rayleigh":
        phase = RayleighPhase()
    elif kind == "penndorf":
        phase = PenndorfPhase()
    elif kind == "henyey-greenstein":
        phase = HenyeyGreensteinPhase(table.spectral("g", **open_unit))
    elif kind == "cornette-shanks":
        phase = CornetteShanksPhase(table.spectral("g", **open_unit))
    else:
        phase = DoubleHenyeyGreensteinPhase(table.spectral("g1", **open_unit),
                                            table.spectral("g2", **open_unit),
                                            table.spectral("alpha", low=0.0, high=1.0))
    table.finish()
    return phase


def _parse_optics(kind: str, table: ConfigTable) -> object:
    try:
        if kind == "rayleigh":
            depolarization = (table.number("depolarization", low=0.0, high=0.5)
                              if table.has("depolarization") else None)
            optics = RayleighOptics(
                gas=table.text("gas", "air"),
                king=table.text("king_factor", "bodhaine-1999"),
                depolarization=depolarization,
                co2_ppm=table.number("co2_ppm", 360.0, low=0.0),
                phase=table.text("phase", "rayleigh", ("rayleigh", "penndorf")))
        elif kind == "absorber":
            if table.has("cross_section") and isinstance(table.data["cross_section"], str):
                cross_section = table.text("cross_section")
            else:
                cross_section = table.spectral("cross_section", low=0.0)
            optics = AbsorberOptics(cross_section)
        elif kind == "angstrom":
            if table.has("optical_depth") == table.has("extinction_per_m"):
                raise ConfigError(f"{table.prefix}: give exactly one of optical_depth "
                                  "(vertical, at the reference wavelength) or extinction_per_m "
                                  "(at density 1)", path=table.path,
                                  key=f"{table.prefix}.optical_depth")
            extinction = (table.number("optical_depth", low=0.0) if table.has("optical_depth")
                          else table.number("extinction_per_m", low=0.0))
            optics = AngstromOptics(
                extinction_at_reference=extinction,
                reference_wavelength_nm=table.number("reference_wavelength_nm", 550.0, low=0.0,
                                                     low_open=True),
                angstrom_exponent=table.number("angstrom_exponent", 0.0),
                single_scattering_albedo=table.spectral("single_scattering_albedo", 1.0,
                                                        low=0.0, high=1.0),
                phase=_parse_phase(table.table("phase")))
        else:
            scattering = table.spectral("scattering_per_m", low=0.0)
            extinction = (table.spectral("extinction_per_m", low=0.0)
                          if table.has("extinction_per_m") else None)
            optics = TabulatedScatteringOptics(
                scattering, extinction, _parse_phase(table.table("phase")))
    except InputError as error:
        raise table.wrap(error) from None
    table.finish()
    return optics
