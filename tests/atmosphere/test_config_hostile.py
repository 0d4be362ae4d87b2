"""Hostile config files: everything that is not a sensible atmosphere is refused before any work
with one ConfigError line naming the file, the key and the value; nothing ends in another
exception, NaN or an atmosphere lost in rounding.

The classes are those of issue 15: files that are not UTF-8 TOML, nesting and keys that make
the TOML reader recurse or grow quadratically, numbers outside their physical range, spectral
polynomials over huge ranges, lists longer than their cost allows. Expected ranges are written
from the physics (a planet from a 1 km asteroid to a brown dwarf, albedos in [0, 1], ...), not
read from `config_ranges`. The property-based test at the end mutates the shipped presets.
"""

import math
import re
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skyscatter.atmosphere import model
from skyscatter.atmosphere.config import (
    MAX_SCATTERING_ORDERS,
    PRESETS_DIR,
    load_atmosphere,
)
from skyscatter.atmosphere.variants import scaled_constituent
from skyscatter.errors import ConfigError, InputError
from skyscatter.transport.single_scattering import SingleScatteringSolver

EARTH = (PRESETS_DIR / "earth.toml").read_text(encoding="utf-8")
HAZE = """name = "haze"
[planet]
radius_m = RADIUS
[star]
[atmosphere]
top_altitude_m = TOP
[[constituent]]
name = "haze"
density = { type = "exponential", scale_height_m = HEIGHT }
[constituent.optics]
type = "angstrom"
optical_depth = 0.1
angstrom_exponent = 1.0
phase = { type = "henyey-greenstein", g = 0.7 }
"""
HAZE_OPTICS = HAZE[HAZE.index("[constituent.optics]"):]


def _haze(radius="6_371_000.0", top="100_000.0", height="2_000.0"):
    return HAZE.replace("RADIUS", radius).replace("TOP", top).replace("HEIGHT", height)


def _refused(path, *phrases):
    """The ConfigError of loading `path`: one line, starting with the file, with `phrases`."""
    with pytest.raises(ConfigError) as info:
        load_atmosphere(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message and len(message) < 600
    for phrase in phrases:
        assert phrase in message, message
    return info.value


def _write(tmp_path, data, name="bad.toml"):
    path = tmp_path / name
    path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
    return path


# --- 1. files that are not UTF-8 TOML ----------------------------------------------------------

@pytest.mark.parametrize(("data", "phrase"), [
    (bytes(range(256)) * 4, "a NUL byte at offset 0"),                    # binary
    (EARTH.encode("utf-16"), "is UTF-16 text, not UTF-8"),                # with byte-order mark
    (EARTH.encode("utf-16-le"), "a NUL byte at offset 1"),                # without one
    (EARTH.replace("Earth", "Erd\xe9").encode("latin-1"), "byte 0xe9 on line 2"),
    (b"", "is empty"),
    (b"# a comment\n\n", "is empty"),
    (b"a = " + b"[" * 10_000 + b"]" * 10_000, "nested too deeply"),
    (b"a = " + b"{b = " * 10_000 + b"1" + b"}" * 10_000, "nested too deeply"),
    # tomllib's memory grows with the square of a dotted key: 40 000 parts took 6 GiB
    (b"a" + b".a" * 100_000 + b" = 1", "a dotted key of more than 64 parts on line 1"),
    (b"[a" + b".a" * 100_000 + b"]", "a dotted key of more than 64 parts on line 1"),
    (EARTH.encode() + b"#" * 2**20, "is larger than 1 MiB"),
    (b"x = " + b"1" * 5000, "an integer with more than 4300 digits"),
])
def test_file_that_is_not_utf8_toml_is_one_line_naming_the_file(tmp_path, data, phrase):
    _refused(_write(tmp_path, data), phrase)


def test_directory_and_device_are_not_config_files(tmp_path):
    (tmp_path / "dir.toml").mkdir()
    _refused(tmp_path / "dir.toml", "is a directory")
    path = tmp_path / "fifo.toml"
    try:
        import os
        os.mkfifo(path)
    except (AttributeError, OSError):
        pytest.skip("no named pipes here")
    _refused(path, "is not a regular file")


def test_utf8_byte_order_mark_is_accepted(tmp_path):
    # Windows editors write one; TOML is UTF-8 either way.
    atmosphere = load_atmosphere(_write(tmp_path, b"\xef\xbb\xbf" + _haze().encode()))
    assert atmosphere.name == "haze"


# --- 2. numbers outside their physical range ---------------------------------------------------

@pytest.mark.parametrize(("old", "new", "key", "allowed"), [
    # a planet between a 1 km asteroid and a brown dwarf; 1e30 m used to give radiance 0
    ("radius_m = 6_371_000.0", "radius_m = 1e30", "planet.radius_m", ">= 1000 and <= 1e+09"),
    ("radius_m = 6_371_000.0", "radius_m = 10.0", "planet.radius_m", ">= 1000"),
    ("radius_m = 6_371_000.0", "radius_m = 1" + "0" * 400, "planet.radius_m", "<= 1e+09"),
    ("ground_albedo = 0.1", "ground_albedo = nan", "planet.ground_albedo", "<= 1"),
    ("distance_au = 1.0", "distance_au = 1e308", "star.distance_au", "<= 1e+06"),
    ("top_altitude_m = 100_000.0", "top_altitude_m = inf", "atmosphere.top_altitude_m",
     "a finite number"),
    ("top_altitude_m = 100_000.0", "top_altitude_m = 1e-300", "atmosphere.top_altitude_m",
     ">= 1"),
    ("co2_ppm = 360.0", "co2_ppm = 1e30", "constituent[0].optics.co2_ppm", "<= 10000"),
    ("column_dobson = 300.0", "column_dobson = -inf", "constituent[1].column_dobson", ">= 0"),
    ("optical_depth = 0.1", "optical_depth = 1e308", "constituent[2].optics.optical_depth",
     "<= 1000"),
    ("angstrom_exponent = 1.14", "angstrom_exponent = 1e30",
     "constituent[2].optics.angstrom_exponent", "<= 6"),
    ("scale_height_m = 2_000.0", "scale_height_m = 1e-300", "constituent[2].density.scale_height_m",
     ">= 1"),
    ("g = 0.65", "g = -1.0", "constituent[2].optics.phase.g", ">= -0.999999"),
])
def test_meaningless_number_is_refused_naming_key_value_and_range(tmp_path, old, new, key,
                                                                   allowed):
    assert old in EARTH
    (tmp_path / "ussa1976_air.csv").write_bytes((PRESETS_DIR / "ussa1976_air.csv").read_bytes())
    (tmp_path / "ussa1976_ozone.csv").write_bytes(
        (PRESETS_DIR / "ussa1976_ozone.csv").read_bytes())
    error = _refused(_write(tmp_path, EARTH.replace(old, new)), f"{key} = ", allowed)
    assert error.key == key


GAS = """[planet]
radius_m = 6_371_000.0
[star]
[atmosphere]
top_altitude_m = 100_000.0
[gas]
surface_temperature_k = 288.15
SURFACE
gravity_m_s2 = 9.80665
composition = { n2 = 0.78, o2 = 0.21, ar = 0.01 }
"""


@pytest.mark.parametrize(("surface", "key", "allowed"), [
    # 1e308 kg m^-3 overflowed later; a gas denser than liquid water is no gas
    ("surface_density_kg_m3 = 1e308", "gas.surface_density_kg_m3", "<= 1000"),
    ("surface_pressure_pa = 1e9", "gas.surface_pressure_pa", "<= 1e+08"),
    ("surface_number_density_m3 = 1e300", "gas.surface_number_density_m3", "<= 1e+29"),
])
def test_gas_surface_values_beyond_a_gas_are_refused(tmp_path, surface, key, allowed):
    _refused(_write(tmp_path, GAS.replace("SURFACE", surface)), key, allowed)


def test_planet_mass_whose_gravity_is_no_planets_is_refused(tmp_path):
    # g = G M / R^2 = 6.674e-11 * 1e30 / 1e6 = 6.7e13 m s^-2: not a planet, not a brown dwarf
    text = GAS.replace("SURFACE", "surface_pressure_pa = 1e5").replace(
        "gravity_m_s2 = 9.80665\n", "").replace("radius_m = 6_371_000.0",
                                                "radius_m = 1000.0\nmass_kg = 1e30")
    _refused(_write(tmp_path, text), "planet.mass_kg = 1e+30", "6.67e+13 m s^-2")


def test_values_each_in_range_that_multiply_into_no_light_name_the_constituent(tmp_path):
    # 1e30 m^-3 of air is in range as a density, but its Rayleigh optical depth at 280 nm is
    # ~4e4: refused naming the constituent, the depth and the wavelength.
    text = _haze().replace('density = { type = "exponential", scale_height_m = 2_000.0 }',
                           'density = { type = "exponential", scale_height_m = 8_000.0, '
                           'surface_density = 1e30 }').replace(
        HAZE_OPTICS, 'optics = { type = "rayleigh" }\n')
    error = _refused(_write(tmp_path, text), "constituent[0] ('haze'): vertical optical depth",
                     "at 280.5 nm", "<= 1000")
    assert error.key == "constituent[0]"


@pytest.mark.parametrize(("radius", "top"), [("1e3", "1.0"), ("1e3", "1e8"), ("1e9", "1.0"),
                                             ("1e9", "1e8")])
def test_corners_of_planet_and_atmosphere_ranges_give_the_closed_form_transmittance(
        tmp_path, radius, top):
    # At every corner of the allowed (radius, top) ranges the zenith transmittance from the
    # ground is exp(-tau) for the vertical optical depth asked for (0.1 at 550 nm): the
    # geometry stays resolved in float64 (at a radius of 1e30 m it came out 1, radiance 0).
    # Tolerance 2e-3: the solver's 64-sample ray-marching of an exponential of scale height
    # top / 5 (1 m for the 1 m atmosphere).
    height = repr(max(1.0, float(top) / 5.0))
    atmosphere = load_atmosphere(_write(tmp_path, _haze(radius, top, height)))
    profile = atmosphere.optical_profile([550.0], monochromatic=True)
    solver = SingleScatteringSolver(profile, n_samples=64)
    ground = np.array([0.0, 0.0, float(radius)])
    transmittance = solver.transmittance(ground, np.array([[0.0, 0.0, 1.0]]))
    assert float(np.ravel(transmittance)[0]) == pytest.approx(math.exp(-0.1), rel=2e-3)
    sun = np.array([0.5, 0.0, math.sqrt(0.75)])
    radiance = solver.sky_radiance(ground, np.array([[0.0, 0.0, 1.0]]), sun)
    assert np.all(np.isfinite(radiance)) and np.all(np.asarray(radiance) > 0.0)


@pytest.mark.parametrize(("optics", "key", "phrase"), [
    # Hansen & Travis b near 0.5: the gamma shape (1 - 2b)/b -> 0 and the radius quadrature
    # underflowed to 0 m (a math domain error before)
    ('size_distribution = { type = "modified-gamma", effective_radius_um = 1.0, '
     'effective_variance = 0.4999 }', "size_distribution.effective_variance", "<= 0.45"),
    ('size_distribution = { type = "gamma", shape = 0.01, scale_um = 1.0 }',
     "size_distribution.shape", ">= 0.1"),
    ('size_distribution = { type = "log-normal", effective_radius_um = 1.0, '
     'effective_variance = 1e-300 }', "size_distribution.effective_variance", ">= 0.0001"),
    ('size_distribution = { type = "log-normal", median_radius_um = 1e-300, '
     'geometric_std = 1.5 }', "size_distribution.median_radius_um", ">= 0.001"),
])
def test_particle_sizes_beyond_the_quadrature_are_refused(tmp_path, optics, key, phrase):
    text = _haze().replace(HAZE_OPTICS, f'optics = {{ type = "mie", refractive_index = '
                           f'{{ real = 1.5 }}, radii = 16, {optics} }}\n')
    _refused(_write(tmp_path, text), f"constituent[0].optics.{key} = ", phrase)


def test_layer_that_grows_past_float64_is_refused(tmp_path):
    # e^(0.01 m^-1 x 100 km) = e^1000 overflows; 0 x inf was NaN in the density.
    text = _haze().replace('density = { type = "exponential", scale_height_m = 2_000.0 }',
                           'density = { type = "layers", layers = [{ exp_scale_per_m = 0.01 }] }')
    _refused(_write(tmp_path, text), "layers[0].exp_scale_per_m = 0.01", "<= 0.007 m^-1")


def test_text_with_control_characters_is_refused(tmp_path):
    text = _haze().replace('name = "haze"\n', 'name = "sky\\u001b[2J\\nfake: line"\n', 1)
    _refused(_write(tmp_path, text), "name = 'sky\\x1b[2J\\nfake: line'", "control characters")


@pytest.mark.parametrize("factor", [math.inf, math.nan, -1.0, 1e7])
def test_scaled_constituent_refuses_factors_that_are_no_amount(factor):
    # inf passed `factor >= 0` and reached the solvers as NaN optics
    with pytest.raises(InputError, match=r"the factor of aerosol = .* is not allowed: a finite "
                                         r"number >= 0 and <= 1e\+06"):
        scaled_constituent(load_atmosphere("earth"), "aerosol", factor)


# --- 3. spectral polynomials ------------------------------------------------------------------

@pytest.mark.parametrize(("value", "phrase"), [
    # range_nm = [1, 1e300] was tabulated on 1e299 points: an internal error
    ("{ polynomial_nm = [0.1], range_nm = [1.0, 1e300] }", "range_nm = [1.0, 1e+300]"),
    ("{ polynomial_nm = [0.1], range_nm = [400.0, 1e9] }", "<= 100000"),
    ("{ polynomial_nm = [0.1], range_nm = [830.0, 360.0] }", "low < high"),
    ("{ polynomial_nm = [0.1, 0, 0, 0, 0, 0, 0, 0, 0, 1e-30], range_nm = [360.0, 830.0] }",
     "at most 9 coefficients"),
    # overflows to inf on the range: was accepted as NaN values (nan < low is False)
    ("{ polynomial_nm = [0.0, 0.0, 1e308], range_nm = [360.0, 830.0] }",
     "at 360 nm it is inf"),
])
def test_spectral_polynomial_outside_the_usable_range_is_refused(tmp_path, value, phrase):
    text = _haze().replace('radius_m = 6_371_000.0', f'radius_m = 6_371_000.0\nground_albedo = '
                                                     f'{value}')
    _refused(_write(tmp_path, text), "planet.ground_albedo", phrase)


# --- 4. lengths that cost too much ------------------------------------------------------------

CONSTITUENT = """[[constituent]]
name = "cNAME"
density = { type = "exponential", scale_height_m = 8000.0 }
optics = { type = "coefficients", scattering_per_m = 1e-7, phase = { type = "rayleigh" } }
"""


def test_more_constituents_than_tables_can_hold_are_refused_with_the_cost(tmp_path):
    head = _haze().split("[[constituent]]")[0]
    sixteen = head + "".join(CONSTITUENT.replace("NAME", str(i)) for i in range(16))
    assert len(load_atmosphere(_write(tmp_path, sixteen)).constituents) == 16
    seventeen = sixteen + CONSTITUENT.replace("NAME", "16")
    _refused(_write(tmp_path, seventeen), "17 constituents, more than 16", "84 MB")


def test_more_layers_gases_and_list_entries_than_allowed_are_refused(tmp_path):
    layers = ", ".join(f"{{ top_altitude_m = {i}.0, constant = 0.5 }}" for i in range(101))
    text = _haze().replace('{ type = "exponential", scale_height_m = 2_000.0 }',
                           f'{{ type = "layers", layers = [{layers}] }}')
    _refused(_write(tmp_path, text), "density.layers has 101 entries, more than 100")
    composition = ", ".join(f"x{i} = 0.01" for i in range(65))
    _refused(_write(tmp_path, GAS.replace("SURFACE", "surface_pressure_pa = 1e5").replace(
        "{ n2 = 0.78, o2 = 0.21, ar = 0.01 }", f"{{ {composition} }}")), "at most 64 gases")
    values = ", ".join(["1"] * 100_001)  # 300 kB: within the file limit
    text = _haze().replace('{ type = "exponential", scale_height_m = 2_000.0 }',
                           f'{{ type = "table", altitude_m = [0, 1], value = [{values}] }}')
    _refused(_write(tmp_path, text), "density.value = [1, 1, 1", "at most 100000 numbers")


def test_csv_profile_longer_than_allowed_is_refused_without_reading_it_all(tmp_path):
    rows = "".join(f"{i},1.0\n" for i in range(100_001))
    (tmp_path / "long.csv").write_text("altitude_m,n\n" + rows)
    text = _haze().replace('{ type = "exponential", scale_height_m = 2_000.0 }',
                           '{ type = "table", file = "long.csv" }')
    _refused(_write(tmp_path, text), "density.file = 'long.csv'", "it has 100001 rows")


# --- 5. the scattering-order cap ------------------------------------------------------------

def test_scattering_order_cap_is_one_named_constant():
    # the CLI's --orders and the API import it from the config module
    assert MAX_SCATTERING_ORDERS == model.MAX_SCATTERING_ORDERS == 1000


# --- property-based: mutated presets ----------------------------------------------------------

MIE = """name = "mie"
[planet]
radius_m = 3_389_500.0
[star]
distance_au = 1.524
[atmosphere]
top_altitude_m = 80_000.0
[[constituent]]
name = "dust"
density = { type = "exponential", scale_height_m = 11_100.0, surface_density = 1.0 }
[constituent.optics]
type = "mie"
size_distribution = { type = "modified-gamma", effective_radius_um = 1.6, effective_variance = 0.2 }
refractive_index = { real = 1.5, imaginary = 0.003 }
radii = 16
optical_depth = 0.5
reference_wavelength_nm = 880.0
blend = { type = "double-henyey-greenstein", g1 = 0.6, g2 = -0.2, alpha = 0.9 }
"""
PRESETS = {name: (PRESETS_DIR / f"{name}.toml").read_text(encoding="utf-8") for name in (
    "earth", "earth-bruneton", "earth-physical", "mars-costa", "mars-physical",
    "super-earth-10bar", "exo-dense-n2", "mars-collienne", "earth-overcast", "earth-fog",
    "mars-dust-storm")}
PRESETS["mie"] = MIE
# The Mie presets with 16 radii instead of 5000: Mie in milliseconds, not seconds
for _name in ("mars-physical", "earth-overcast", "earth-fog", "mars-dust-storm"):
    PRESETS[_name] = PRESETS[_name].replace('type = "mie"\n', 'type = "mie"\nradii = 16\n')
NUMBER = re.compile(r"(?<=[=\[,{]) *(-?[0-9][0-9_.eE+-]*)")
KEY_BEFORE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*=\s*[\[{ ]*$")


def _document(text):
    document = tomllib.loads(text)
    document.pop("sources", None)
    document.pop("description", None)
    return repr(document)


def _number_sites(text):
    """(start, end, key) of every number that is a value of the document (not in a string or a
    comment: replacing it changes the parsed document)."""
    sites, original = [], _document(text)
    for match in NUMBER.finditer(text):
        line_start = text.rfind("\n", 0, match.start(1)) + 1
        key = KEY_BEFORE.search(text[line_start:match.start(1)].rsplit(",", 1)[-1]
                                .rsplit("{", 1)[-1])
        changed = text[:match.start(1)] + "7" + text[match.end(1):]
        try:
            if _document(changed) == original:
                continue
        except tomllib.TOMLDecodeError:
            continue
        sites.append((match.start(1), match.end(1), key.group(1) if key else None))
    return sites


SITES = {name: _number_sites(text) for name, text in PRESETS.items()}
HOSTILE = st.one_of(
    st.sampled_from(["nan", "-nan", "inf", "-inf", "1e308", "-1e308", "1e30", "-1e30", "0",
                     "-0.0", "-1", "1e-300", "5e-324", "true", '"7"', '""', "[]", "{}",
                     "[1.0, 2.0]", "{ a = 1 }", "1979-05-27", "07:32:00", '"\\u0000"',
                     '"\\u202e1"', "1" + "0" * 400, "0x7fffffffffffffff", "9" * 40]),
    st.floats().map(lambda x: "nan" if math.isnan(x) else "inf" if x == math.inf else
                    "-inf" if x == -math.inf else repr(x)),
    st.integers(min_value=-(2**80), max_value=2**80).map(str),
)
WHOLE_FILES = st.one_of(
    st.binary(max_size=200),
    st.text(max_size=200).map(lambda t: t.encode("utf-8")),
    st.integers(min_value=300, max_value=3000).map(lambda n: b"a = " + b"[" * n + b"]" * n),
    st.text(max_size=50).map(lambda t: t.encode("utf-16")),
)


def _check(path, mutated_key):
    """load_atmosphere(path) gives finite optics or one ConfigError line naming the file and
    the mutated key (or the constituent, when values in range multiply into too much)."""
    try:
        atmosphere = load_atmosphere(path)
    except ConfigError as error:
        message = str(error)
        assert message.startswith(f"{path}: ") and "\n" not in message, message
        assert len(message) < 1000, message
        if mutated_key is not None:
            assert (mutated_key in message or "vertical optical depth" in message
                    or "density profile that is not zero" in message), message
        return
    profile = atmosphere.optical_profile(np.linspace(360.0, 830.0, 12))
    for array in (profile.density, profile.extinction_per_density,
                  profile.scattering_per_density, profile.ground_albedo,
                  profile.toa_irradiance):
        assert np.all(np.isfinite(array))


SETTINGS = settings(max_examples=100, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])


@SETTINGS
@given(data=st.data(), value=HOSTILE)
def test_mutated_preset_loads_finite_or_is_one_config_error_naming_the_key(tmp_path, data,
                                                                            value):
    name = data.draw(st.sampled_from(sorted(PRESETS)))
    start, end, key = data.draw(st.sampled_from(SITES[name]))
    text = PRESETS[name]
    for csv in ("ussa1976_air.csv", "ussa1976_ozone.csv"):
        (tmp_path / csv).write_bytes((PRESETS_DIR / csv).read_bytes())
    _check(_write(tmp_path, text[:start] + value + text[end:], f"{name}.toml"), key)


@SETTINGS
@given(data=WHOLE_FILES)
def test_any_bytes_load_or_are_one_config_error_naming_the_file(tmp_path, data):
    _check(_write(tmp_path, data, "any.toml"), None)
