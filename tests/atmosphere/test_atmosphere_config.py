"""Atmosphere configs: the documented worked example and the presets against published numbers,
closed forms for profiles, and one clear ConfigError per kind of bad file.

The worked example is read from the ```toml block under "## Worked example" in docs/config.md,
so the docs cannot drift from what the loader accepts and computes.
"""

import dataclasses
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from skyscatter.atmosphere.config import (
    PRESETS_DIR,
    list_presets,
    load_atmosphere,
    outline_atmosphere,
)
from skyscatter.errors import ConfigError, InputError

PERCENT = 1e-2
DOCS_CONFIG = Path(__file__).resolve().parents[2] / "docs" / "config.md"
# 1 DU = 10 µm of pure gas at 273.15 K and 101325 Pa:
# 1e-5 m x Loschmidt's 2.6867811e25 m^-3 (CODATA 2018)
DOBSON_UNIT_M2 = 2.6867811e20


def _vertical_optical_depth(atmosphere, wavelengths_nm, monochromatic=False):
    """Vertical optical depth per constituent, ground to top, shape (n_c, n_wl), and the names."""
    profile = atmosphere.optical_profile(wavelengths_nm, monochromatic=monochromatic)
    column = np.trapezoid(profile.density, profile.altitudes_m, axis=1)
    return column[:, None] * profile.extinction_per_density, profile


def _toml_blocks(markdown: str) -> list[str]:
    return re.findall(r"^```toml\n(.*?)^```", markdown, flags=re.S | re.M)


def _worked_example_text() -> str:
    text = DOCS_CONFIG.read_text(encoding="utf-8")
    section = text.split("\n## Worked example", 1)
    assert len(section) == 2, "docs/config.md lost its '## Worked example' section"
    return _toml_blocks(section[1])[0]


@pytest.fixture(scope="module")
def worked_example(tmp_path_factory):
    text = _worked_example_text()
    path = tmp_path_factory.mktemp("docs") / "clear-sky.toml"
    path.write_text(text, encoding="utf-8")
    raw = tomllib.loads(text)
    by_kind = {c["optics"]["type"]: c for c in raw["constituent"]}
    return load_atmosphere(path), raw, by_kind


# --- the worked example of docs/config.md -------------------------------------------------------

@pytest.mark.parametrize(("wavelength_nm", "bodhaine_tau"), [(400.0, 0.3602), (550.0, 0.0971),
                                                             (700.0, 0.0364)])
def test_worked_example_rayleigh_depth_matches_bodhaine_1999_eq30(worked_example, wavelength_nm,
                                                                  bodhaine_tau):
    # Reference: Bodhaine et al. 1999 eq. 30 (1013.25 hPa, 360 ppm CO2). Ours: the example's
    # USSA-1976 air column (22 rows,
    # 0.14 % below the full table; 0.3 % below Bodhaine's 2.1544e25 cm^-2) x our cross-section.
    # Tolerance 1 %: column (0.4 %) + King-factor/refractivity conventions (0.5 %) + rounding.
    atmosphere, _, by_kind = worked_example
    tau, profile = _vertical_optical_depth(atmosphere, [wavelength_nm], monochromatic=True)
    air = profile.names.index(by_kind["rayleigh"]["name"])
    assert tau[air, 0] == pytest.approx(bodhaine_tau, rel=1 * PERCENT)


def test_worked_example_ozone_column_is_the_dobson_units_asked_for(worked_example):
    # Closed form: column [m^-2] / 2.6867811e20 = DU. Tolerance 0.1 %: the loader scales on a
    # 20001-level trapezoid, the solvers' profile has 2001 levels (linear table: < 0.01 % apart).
    atmosphere, _, by_kind = worked_example
    _, profile = _vertical_optical_depth(atmosphere, [550.0])
    ozone = profile.names.index(by_kind["absorber"]["name"])
    column_du = np.trapezoid(profile.density[ozone], profile.altitudes_m) / DOBSON_UNIT_M2
    assert column_du == pytest.approx(by_kind["absorber"]["column_dobson"], rel=0.1 * PERCENT)


def test_worked_example_aerosol_depth_is_the_aod_and_follows_the_angstrom_law(worked_example):
    # AOD at the reference wavelength = optical_depth; elsewhere tau(lam) = tau0 (lam/lam0)^-alpha
    # (Angstrom 1929, closed form). Tolerance 0.1 %: trapezoid on 2001 levels of a 1.5 km scale
    # height, (dz/H)^2/12 = 1e-4.
    atmosphere, _, by_kind = worked_example
    optics = by_kind["angstrom"]["optics"]
    lam0 = optics["reference_wavelength_nm"]
    wavelengths = np.array([440.0, lam0, 870.0])
    tau, profile = _vertical_optical_depth(atmosphere, wavelengths)
    aerosol = profile.names.index(by_kind["angstrom"]["name"])
    expected = optics["optical_depth"] * (wavelengths / lam0) ** -optics["angstrom_exponent"]
    np.testing.assert_allclose(tau[aerosol], expected, rtol=0.1 * PERCENT)
    ssa = profile.scattering_per_density[aerosol] / profile.extinction_per_density[aerosol]
    np.testing.assert_allclose(ssa, optics["single_scattering_albedo"], rtol=1e-12)
    g = profile.phases[aerosol].asymmetry(wavelengths)
    np.testing.assert_allclose(g, optics["phase"]["g"], rtol=1e-12)


def test_worked_example_ground_and_star(worked_example):
    atmosphere, raw, _ = worked_example
    profile = atmosphere.optical_profile([450.0, 550.0, 650.0])
    np.testing.assert_allclose(profile.ground_albedo, raw["planet"]["ground_albedo"])
    assert atmosphere.bottom_radius_m == raw["planet"]["radius_m"]
    assert atmosphere.top_altitude_m == raw["atmosphere"]["top_altitude_m"]
    # ASTM G173-03 ETR near 550 nm: 1.863 W m^-2 nm^-1 (pvlib's ASTMG173.csv); 2 %: bin averaging.
    assert profile.toa_irradiance[1] == pytest.approx(1.863, rel=2 * PERCENT)


def test_every_toml_snippet_in_the_config_docs_loads(tmp_path):
    # Snippets are fragments: complete them with a minimal planet/star/atmosphere around them.
    base = {"planet": '[planet]\nradius_m = 6_371_000.0\n', "star": '[star]\n',
            "atmosphere": '[atmosphere]\ntop_altitude_m = 100_000.0\n'}
    gas = ('[[constituent]]\nname = "gas"\ndensity = { type = "exponential", scale_height_m = '
           '8000.0 }\noptics = { type = "coefficients", scattering_per_m = 1e-5, '
           'phase = { type = "rayleigh" } }\n')
    (tmp_path / "ozone.csv").write_text("altitude_m,number_density_m3\n0,1e18\n60000,1e16\n")
    blocks = _toml_blocks(DOCS_CONFIG.read_text(encoding="utf-8"))
    assert len(blocks) >= 5
    for index, block in enumerate(blocks):
        if "[planet]" in block:
            text = block
        elif block.lstrip().startswith("[star]"):
            text = base["planet"] + block + base["atmosphere"] + gas
        elif "[[constituent]]" in block:
            text = base["planet"] + base["star"] + base["atmosphere"] + block
        else:  # a bare planet key
            text = base["planet"] + block + base["star"] + base["atmosphere"] + gas
        path = tmp_path / f"snippet{index}.toml"
        path.write_text(text, encoding="utf-8")
        atmosphere = load_atmosphere(path)
        tau, _ = _vertical_optical_depth(atmosphere, [450.0, 550.0])
        assert np.all(np.isfinite(tau)) and np.all(tau >= 0.0), block


# --- presets ----------------------------------------------------------------------------------

def test_list_presets_names_the_shipped_files_with_descriptions():
    presets = list_presets()
    assert set(presets) == {p.stem for p in PRESETS_DIR.glob("*.toml")}
    assert {"earth", "earth-bruneton", "mars-costa"} <= set(presets)
    assert all(description.strip() for description in presets.values())


@pytest.mark.parametrize("name", sorted(p.stem for p in PRESETS_DIR.glob("*.toml")))
def test_each_preset_loads_with_finite_optics(name):
    atmosphere = load_atmosphere(name)
    wavelengths = np.linspace(360.0, 830.0, 48)
    tau, profile = _vertical_optical_depth(atmosphere, wavelengths)
    assert np.all(np.isfinite(tau)) and np.all(tau >= 0.0)
    assert np.all(profile.scattering_per_density <= profile.extinction_per_density * (1 + 1e-12))
    assert np.all((profile.ground_albedo >= 0.0) & (profile.ground_albedo <= 1.0))
    assert np.all(profile.toa_irradiance > 0.0)
    assert len(set(profile.names)) == len(profile.names)


@pytest.mark.parametrize("name", sorted(p.stem for p in PRESETS_DIR.glob("*.toml")))
def test_a_preset_s_outline_names_what_loading_it_builds(name, monkeypatch):
    # the outline reads the same config without building the optics: no Mie computation may
    # run for it, and every field agrees with the atmosphere that loading builds
    def no_mie(*args, **kwargs):
        raise AssertionError("the outline built Mie optics")

    with monkeypatch.context() as patched:
        patched.setattr("skyscatter.atmosphere.particle_config.particle_optics", no_mie)
        outline = outline_atmosphere(name)
    atmosphere = load_atmosphere(name)
    assert outline.name == atmosphere.name and outline.description == atmosphere.description
    assert outline.body == atmosphere.planet.body
    assert outline.constituents == tuple(c.name for c in atmosphere.constituents)
    assert outline.radius_m == atmosphere.bottom_radius_m
    assert outline.top_altitude_m == atmosphere.top_altitude_m
    assert outline.mean_ground_albedo == pytest.approx(
        np.mean(atmosphere.planet.ground_albedo.values), rel=1e-15)


def _half_unit_of_last_digit(text: str) -> float:
    decimals = len(text.split(".")[1]) if "." in text else 0
    return 0.5 * 10.0**-decimals


@pytest.mark.parametrize(("constituent", "wavelength_nm", "printed"), [
    ("rayleigh", 680.0, "0.0464"), ("rayleigh", 550.0, "0.1084"), ("rayleigh", 440.0, "0.2647"),
    ("mie", 680.0, "0.00533"), ("mie", 550.0, "0.00533"), ("mie", 440.0, "0.00533"),
    ("ozone", 680.0, "0.00975"), ("ozone", 550.0, "0.0282"), ("ozone", 440.0, "0.00128"),
])
def test_earth_bruneton_depths_match_bruneton_2017_demo(constituent, wavelength_nm, printed):
    # Reference: vertical optical depths derived by hand from Bruneton 2017's demo.cc parameters
    # (InitModel). The ozone cross-section there is a table of
    # 10-nm bin means, which our config interpolates point-wise: monochromatic=True, and at the
    # bin centres 440/550/680 it returns the tabulated value itself.
    # Tolerance: half a unit in the last printed digit (0.4 % for 0.00128) + 0.1 % for our
    # 60 km top (e^-7.5 = 0.06 % of the Rayleigh column) and the 2001-level trapezoid.
    tau, profile = _vertical_optical_depth(load_atmosphere("earth-bruneton"), [wavelength_nm],
                                           monochromatic=True)
    value = tau[profile.names.index(constituent), 0]
    reference = float(printed)
    assert value == pytest.approx(reference,
                                  abs=_half_unit_of_last_digit(printed) + 0.1 * PERCENT * reference)


def test_earth_preset_matches_its_cited_numbers():
    # Sources cited in earth.toml: ozone 300 DU; the SPECTRL2 rural aerosol (Bird & Riordan 1986,
    # pvlib defaults) tau(500 nm) = 0.1 with Angstrom exponent 1.14; USSA-1976 air, whose
    # Rayleigh depth is Bodhaine 1999 eq. 30: 0.0971 at 550 nm (tolerance as in the worked
    # example). Aerosol 0.1 %: trapezoid on 2001 levels, (dz/H)^2/12 = 5e-5 for H = 2 km.
    tau, profile = _vertical_optical_depth(load_atmosphere("earth"), [500.0, 550.0],
                                           monochromatic=True)
    names = profile.names
    ozone_du = np.trapezoid(profile.density[names.index("ozone")], profile.altitudes_m)
    assert ozone_du / DOBSON_UNIT_M2 == pytest.approx(300.0, rel=0.1 * PERCENT)
    np.testing.assert_allclose(tau[names.index("aerosol")],
                               0.1 * (np.array([500.0, 550.0]) / 500.0) ** -1.14,
                               rtol=0.1 * PERCENT)
    assert tau[names.index("air"), 1] == pytest.approx(0.0971, rel=1 * PERCENT)


# --- closed forms -----------------------------------------------------------------------------

BASE = """\
name = "test"
[planet]
radius_m = 6_371_000.0
ground_albedo = 0.2
[star]
type = "sun"
[atmosphere]
top_altitude_m = TOP
[[constituent]]
name = "haze"
density = { type = "exponential", scale_height_m = 2000.0 }
[constituent.optics]
type = "angstrom"
optical_depth = 0.1
angstrom_exponent = 1.3
phase = { type = "henyey-greenstein", g = 0.7 }
"""


def _config(tmp_path, text, top="100_000.0", name="sky.toml"):
    path = tmp_path / name
    path.write_text(text.replace("TOP", top), encoding="utf-8")
    return path


@pytest.mark.parametrize(("scale_height_m", "top_m"), [(1_200.0, 60_000.0), (8_000.0, 100_000.0),
                                                       (8_000.0, 20_000.0)])
def test_exponential_profile_depth_is_the_closed_form(tmp_path, scale_height_m, top_m):
    # tau = beta * n0 * H * (1 - exp(-top/H)) (integral of an exponential). Tolerance: the
    # trapezoid rule on 2001 levels errs by (dz/H)^2/12 = 1.5e-4 for H = 1.2 km, dz = 30 m.
    beta, n0 = 1.3e-5, 2.5
    text = BASE.replace(
        'density = { type = "exponential", scale_height_m = 2000.0 }',
        f'density = {{ type = "exponential", scale_height_m = {scale_height_m}, '
        f'surface_density = {n0} }}').replace(
        "optical_depth = 0.1", f"extinction_per_m = {beta}")
    atmosphere = load_atmosphere(_config(tmp_path, text, top=str(top_m)))
    tau, _ = _vertical_optical_depth(atmosphere, [550.0])
    closed_form = beta * n0 * scale_height_m * (1.0 - math.exp(-top_m / scale_height_m))
    assert tau[0, 0] == pytest.approx(closed_form, rel=3e-4)


def test_table_profile_from_csv_equals_the_same_table_inline(tmp_path):
    # log interpolation of an exponential sampled at knots is exact: column = n0 H (1 - e^-top/H)
    z = np.arange(0.0, 100_001.0, 5_000.0)
    n = 2.0e25 * np.exp(-z / 8_000.0)
    rows = "".join(f"{a},{b:.17g}\n" for a, b in zip(z, n, strict=True))
    (tmp_path / "air.csv").write_text("# comment line\naltitude_m,n_m3\n" + rows)
    optics = 'optics = { type = "rayleigh" }'
    inline = BASE.replace(
        'density = { type = "exponential", scale_height_m = 2000.0 }',
        f'density = {{ type = "table", altitude_m = {z.tolist()}, value = {n.tolist()} }}')
    from_file = BASE.replace('density = { type = "exponential", scale_height_m = 2000.0 }',
                             'density = { type = "table", file = "air.csv", column = "n_m3" }')
    columns = []
    for name, text in (("inline.toml", inline), ("file.toml", from_file)):
        text = text.split("[constituent.optics]")[0] + optics + "\n"
        profile = load_atmosphere(_config(tmp_path, text, name=name)).optical_profile([550.0])
        columns.append(np.trapezoid(profile.density[0], profile.altitudes_m))
    closed_form = 2.0e25 * 8_000.0 * (1.0 - math.exp(-100_000.0 / 8_000.0))
    assert columns[0] == pytest.approx(columns[1], rel=1e-12)
    assert columns[0] == pytest.approx(closed_form, rel=1e-4)  # 2001-level trapezoid


# --- bad configs ------------------------------------------------------------------------------

HAZE_DENSITY = 'density = { type = "exponential", scale_height_m = 2000.0 }'


@pytest.mark.parametrize(("old", "new", "key", "value", "extra"), [
    # unknown keys, with a suggestion when one is close
    ('name = "test"', 'descripton = "x"\nname = "test"', "descripton", None,
     "did you mean 'description'"),
    ("ground_albedo = 0.2", "ground_albedo = 0.2\nground_albdo = 0.3", "planet.ground_albdo",
     None, "did you mean 'planet.ground_albedo'"),
    ("scale_height_m = 2000.0", "scale_height_m = 2000.0, scale_heigth_m = 3",
     "constituent[0].density.scale_heigth_m", None,
     "did you mean 'constituent[0].density.scale_height_m'"),
    ("g = 0.7", "g = 0.7, colour = 'red'", "constituent[0].optics.phase.colour", None, None),
    # out of range
    ("scale_height_m = 2000.0", "scale_height_m = -2000.0",
     "constituent[0].density.scale_height_m", "-2000.0", ">= 1 and <= 1e+09"),
    ("ground_albedo = 0.2", "ground_albedo = 1.2", "planet.ground_albedo", "1.2", "<= 1"),
    ("ground_albedo = 0.2", "ground_albedo = { wavelength_nm = [400, 700], value = [0.2, 1.5] }",
     "planet.ground_albedo.value", "1.5", ">= 0 and <= 1"),
    ("g = 0.7", "g = 1.5", "constituent[0].optics.phase.g", "1.5", "<= 0.999999"),
    # missing, wrong type, unknown choice
    ("[planet]\nradius_m = 6_371_000.0\nground_albedo = 0.2\n", "", "[planet]", None,
     "missing"),
    # a required key misspelt: missing, and the file's stray key named
    ("radius_m = 6_371_000.0", "raduis_m = 6_371_000.0", "planet.radius_m", None,
     "is missing (a number is required: a finite number >= 1000 and <= 1e+09); the file has "
     "'planet.raduis_m': misspelt?"),
    ("[planet]", "[planett]", "[planet]", None, "the file has 'planett': misspelt?"),
    ("radius_m = 6_371_000.0", 'radius_m = "6371 km"', "planet.radius_m", "'6371 km'",
     "a finite number"),
    ("ground_albedo = 0.2", "ground_albedo = true", "planet.ground_albedo", "True",
     "a finite number"),
    ('type = "angstrom"', 'type = "t-matrix"', "constituent[0].optics.type", "'t-matrix'",
     "one of: rayleigh, absorber, angstrom, coefficients, mie"),
    ('type = "henyey-greenstein"', 'type = "henyey"', "constituent[0].optics.phase.type",
     "'henyey'", "henyey-greenstein"),
    # contradictory
    ("optical_depth = 0.1", "optical_depth = 0.1\nextinction_per_m = 1e-5",
     "constituent[0].optics", None, "exactly one of optical_depth"),
    # tables
    (HAZE_DENSITY, 'density = { type = "table", altitude_m = [0, 2000, 1000], value = [3, 2, 1] }',
     "constituent[0].density.altitude_m", "[0.0, 2000.0, 1000.0]", "strictly increasing"),
    (HAZE_DENSITY, 'density = { type = "table", altitude_m = [0, 1000], value = [1, -2] }',
     "constituent[0].density.value", "[1, -2]", ">= 0"),
])
def test_bad_config_raises_config_error_naming_file_key_and_value(tmp_path, old, new, key, value,
                                                                    extra):
    assert old in BASE
    path = _config(tmp_path, BASE.replace(old, new, 1), name="bad.toml")
    with pytest.raises(ConfigError) as info:
        load_atmosphere(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert key in message
    if value is not None:
        assert value in message
    if extra is not None:
        assert extra in message
    assert "\n" not in message


def test_missing_csv_file_names_the_config_key_and_file(tmp_path):
    path = _config(tmp_path, BASE.replace(HAZE_DENSITY,
                                          'density = { type = "table", file = "nope.csv" }'))
    with pytest.raises(ConfigError, match=r"constituent\[0\]\.density\.file = 'nope\.csv' .*"
                                          r"readable UTF-8 CSV file .*\(No such file"):
        load_atmosphere(path)


@pytest.mark.parametrize("csv_text", [
    "altitude_m,number_density_m3\n0,1e25\n1000,abc\n",   # not a number
    "altitude_m;number_density_m3\n0;1e25\n1000;1e24\n",  # wrong separator
    "height,number_density_m3\n0,1e25\n1000,1e24\n",      # no altitude_m column
    "altitude_m,number_density_m3\n0,1e25\n1000\n",       # short row
    "",                                                   # empty file
])
def test_csv_with_garbage_is_a_config_error_naming_the_file(tmp_path, csv_text):
    (tmp_path / "air.csv").write_text(csv_text)
    path = _config(tmp_path, BASE.replace(HAZE_DENSITY,
                                          'density = { type = "table", file = "air.csv" }'))
    with pytest.raises(ConfigError) as info:
        load_atmosphere(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert "constituent[0].density.file = 'air.csv'" in message
    assert "altitude_m" in message


@pytest.mark.parametrize(("csv_text", "key"), [
    ("altitude_m,n\n0,1e25\nnan,1e24\n5000,1e23\n", "constituent[0].density.altitude_m"),
    ("altitude_m,n\n0,1e25\n1000,nan\n", "constituent[0].density.value"),
])
def test_csv_with_nan_is_a_config_error(tmp_path, csv_text, key):
    (tmp_path / "air.csv").write_text(csv_text)
    path = _config(tmp_path, BASE.replace(HAZE_DENSITY,
                                          'density = { type = "table", file = "air.csv" }'))
    with pytest.raises(ConfigError, match=re.escape(key) + r" = \[.*nan.*\] is not allowed"):
        load_atmosphere(path)


def test_csv_column_that_is_not_in_the_file_lists_the_columns(tmp_path):
    (tmp_path / "air.csv").write_text("altitude_m,a,b\n0,1,2\n1000,1,2\n")
    path = _config(tmp_path, BASE.replace(
        HAZE_DENSITY, 'density = { type = "table", file = "air.csv", column = "c" }'))
    with pytest.raises(ConfigError, match=r"density\.column = 'c' .*air\.csv: a, b"):
        load_atmosphere(path)


def test_not_valid_toml_names_the_file_and_the_line(tmp_path):
    path = _config(tmp_path, BASE + "\n[planet\n")
    with pytest.raises(ConfigError, match=re.escape(f"{path}: not valid TOML") + r".*line 18"):
        load_atmosphere(path)


def test_unknown_preset_suggests_the_closest_name():
    with pytest.raises(InputError, match=r"unknown preset 'eart'; did you mean 'earth'\?"):
        load_atmosphere("eart")


def test_missing_config_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        load_atmosphere(tmp_path / "missing.toml")


@pytest.mark.parametrize("scale_height_m", [30.0, 100.0, 2000.0])
def test_optical_depth_is_exact_on_the_solver_levels_even_for_thin_layers(tmp_path,
                                                                         scale_height_m):
    # The AOD asked for is what the solver integrates, whatever the layer's thickness relative
    # to the 50 m level spacing (normalised on the levels the solver uses). Tolerance: rounding.
    text = BASE.replace("scale_height_m = 2000.0", f"scale_height_m = {scale_height_m}")
    atmosphere = load_atmosphere(_config(tmp_path, text))
    tau, _ = _vertical_optical_depth(atmosphere, [500.0, 550.0])
    assert tau[0, 1] == pytest.approx(0.1, rel=1e-12)
    assert tau[0, 0] == pytest.approx(0.1 * (500.0 / 550.0) ** -1.3, rel=1e-12)


# --- [tables] -----------------------------------------------------------------------------------

def test_tables_orders_is_read_and_defaults_to_bruneton_4(tmp_path):
    # Default: Bruneton 2017 model.h `Init(num_scattering_orders = 4)`.
    assert load_atmosphere(_config(tmp_path, BASE, name="default.toml")).scattering_orders == 4
    text = BASE.replace("[planet]", "[tables]\norders = 12\n[planet]", 1)
    assert load_atmosphere(_config(tmp_path, text, name="twelve.toml")).scattering_orders == 12
    empty = BASE.replace("[planet]", "[tables]\n[planet]", 1)
    assert load_atmosphere(_config(tmp_path, empty, name="empty.toml")).scattering_orders == 4


@pytest.mark.parametrize(("tables", "key", "shown", "allowed"), [
    ("orders = 0", "tables.orders", "tables.orders = 0", ">= 1"),
    ("orders = -3", "tables.orders", "tables.orders = -3", ">= 1"),
    ("orders = 1001", "tables.orders", "tables.orders = 1001", "<= 1000"),
    ("orders = 2.5", "tables.orders", "tables.orders = 2.5", "an integer"),
    ("orders = 4.0", "tables.orders", "tables.orders = 4.0", "an integer"),
    ('orders = "four"', "tables.orders", "tables.orders = 'four'", "an integer"),
    ("orders = true", "tables.orders", "tables.orders = True", "an integer"),
    ("order = 10", "tables.order", "unknown key 'tables.order'", "did you mean 'tables.orders'"),
])
def test_bad_tables_orders_is_a_config_error_naming_file_key_and_value(tmp_path, tables, key,
                                                                       shown, allowed):
    path = _config(tmp_path, BASE.replace("[planet]", f"[tables]\n{tables}\n[planet]", 1),
                   name="bad.toml")
    with pytest.raises(ConfigError) as info:
        load_atmosphere(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert shown in message and allowed in message
    assert info.value.key == key
    assert "\n" not in message


def test_tables_that_is_not_a_table_and_misspelt_tables_are_rejected(tmp_path):
    path = _config(tmp_path, 'tables = 4\n' + BASE, name="scalar.toml")
    with pytest.raises(ConfigError, match=r"tables = 4 is not allowed: a table"):
        load_atmosphere(path)
    path = _config(tmp_path, BASE.replace("[planet]", "[table]\norders = 4\n[planet]", 1),
                   name="typo.toml")
    with pytest.raises(ConfigError, match=r"unknown key 'table'; did you mean 'tables'\?"):
        load_atmosphere(path)


def test_atmosphere_rejects_scattering_orders_outside_1_to_1000():
    atmosphere = load_atmosphere("earth")
    with pytest.raises(InputError, match="scattering_orders = 0 must be an integer from 1 to "
                                         "1000"):
        dataclasses.replace(atmosphere, scattering_orders=0)
    with pytest.raises(InputError, match="scattering_orders = 1001 must be an integer from 1"):
        dataclasses.replace(atmosphere, scattering_orders=1001)
