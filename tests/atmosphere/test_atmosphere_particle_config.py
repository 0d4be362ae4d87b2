"""`type = "mie"` constituents and spectral polynomials in configs: what the loader builds, and
one clear ConfigError per kind of bad value."""

import numpy as np
import pytest

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.errors import ConfigError
from skyscatter.optics.mie import particle_optics
from skyscatter.optics.particle_index import ComplexIndex
from skyscatter.optics.size_distribution import LogNormal

HEAD = """[planet]
radius_m = 6_371_000.0
[star]
[atmosphere]
top_altitude_m = 50_000.0
[[constituent]]
name = "haze"
density = { type = "exponential", scale_height_m = 2_000.0, surface_density = 1.0 }
[constituent.optics]
type = "mie"
"""
OPTICS = """size_distribution = { type = "log-normal", median_radius_um = 0.2, geometric_std = 1.5 }
refractive_index = { real = 1.44 }
radii = 200
optical_depth = 0.3
reference_wavelength_nm = 500.0
"""


def _load(tmp_path, optics=OPTICS):
    path = tmp_path / "haze.toml"
    path.write_text(HEAD + optics, encoding="utf-8")
    return load_atmosphere(path)


def test_mie_constituent_equals_particle_optics_and_has_the_optical_depth(tmp_path):
    atmosphere = _load(tmp_path)
    profile = atmosphere.optical_profile([450.0, 500.0, 700.0], monochromatic=True)
    # Independent path: the optics module called directly with the same inputs.
    direct = particle_optics(LogNormal(0.2e-6, 1.5), ComplexIndex.constant(1.44),
                             [450.0, 500.0, 700.0], n_radii=200, cache_directory=False)
    np.testing.assert_allclose(profile.extinction_per_density[0],
                               direct.extinction_cross_section_m2, rtol=1e-10)
    tau = np.trapezoid(profile.density[0], profile.altitudes_m) * profile.extinction_per_density[0]
    assert tau[1] == pytest.approx(0.3, rel=1e-9)  # exact on the solver's own levels
    assert tau[0] > tau[1] > tau[2]  # sub-micron droplets: extinction falls with wavelength


@pytest.mark.parametrize(("old", "new", "key"), [
    ('type = "log-normal"', 'type = "lognormal"', "constituent[0].optics.size_distribution.type"),
    ("refractive_index = { real = 1.44 }", 'refractive_index = { material = "gold" }',
     "constituent[0].optics.refractive_index.material"),
    ("radii = 200", "radii = 3", "constituent[0].optics.radii"),
    ("geometric_std = 1.5", "geometric_std = 0.5",
     "constituent[0].optics.size_distribution.geometric_std"),
    ("refractive_index = { real = 1.44 }", "refractive_index = { real = 1.44, imag = 0.1 }",
     "constituent[0].optics.refractive_index.imag"),
])
def test_bad_mie_values_are_config_errors_naming_the_key(tmp_path, old, new, key):
    assert old in OPTICS
    with pytest.raises(ConfigError) as error:
        _load(tmp_path, OPTICS.replace(old, new))
    assert error.value.key == key
    assert "haze.toml" in str(error.value)


def test_spectral_polynomial_is_evaluated_inside_its_range_and_held_outside(tmp_path):
    # Meyran 2022's g1(lambda) (its §4.1): 0.670 / 0.400 / 0.030 at 440 / 550 / 680 nm.
    blend = ('blend = { type = "henyey-greenstein", g = { polynomial_nm = [1.35512821, '
             '-8.39160839e-4, -1.63170163e-6], range_nm = [360.0, 830.0] } }\n')
    atmosphere = _load(tmp_path, OPTICS + blend)
    g = atmosphere.constituents[0].optics.blend.g
    np.testing.assert_allclose(g.at([440.0, 550.0, 680.0]), [0.670, 0.400, 0.030], atol=1e-3)
    assert g.at(900.0) == pytest.approx(g.at(830.0))


def test_polynomial_out_of_range_values_are_a_config_error(tmp_path):
    blend = ('blend = { type = "henyey-greenstein", g = { polynomial_nm = [0.0, 0.01], '
             'range_nm = [360.0, 830.0] } }\n')
    with pytest.raises(ConfigError, match="a polynomial whose values over 360-830 nm are each "
                                          "a finite number >= -0.999999 and <= 0.999999"):
        _load(tmp_path, OPTICS + blend)
