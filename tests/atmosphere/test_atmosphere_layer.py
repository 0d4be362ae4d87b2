"""Uniform layers (`density = { type = "layer" }`, `profiles.UniformLayerProfile`): the profile
against its closed-form column, the altitude levels that resolve it, the optical depth of the
layer presets (earth-overcast, earth-fog, mars-dust-storm) against what they request, and one
clear ConfigError line per bad layer.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from cli_runner import run_cli
from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import DEFAULT_PROFILE_LEVELS, MAX_PROFILE_LEVELS
from skyscatter.atmosphere.profiles import UniformLayerProfile
from skyscatter.errors import ConfigError, InputError
from skyscatter.transport import _kernels

PERCENT = 1e-2

LAYER_CONFIG = """\
name = "layer-test"
[planet]
radius_m = 6_371_000.0
[star]
type = "sun"
[atmosphere]
top_altitude_m = 100_000.0
[[constituent]]
name = "cloud"
density = { type = "layer", LAYER }
[constituent.optics]
type = "coefficients"
scattering_per_m = 0.01
phase = { type = "henyey-greenstein", g = 0.85 }
"""


def _config(tmp_path, layer: str):
    path = tmp_path / "layer.toml"
    path.write_text(LAYER_CONFIG.replace("LAYER", layer), encoding="utf-8")
    return path


# --- the profile --------------------------------------------------------------------------------

@pytest.mark.parametrize(("base", "top", "edge"), [(600.0, 1100.0, 0.0), (600.0, 1100.0, 100.0),
                                                   (0.0, 300.0, 0.0), (0.0, 300.0, 100.0),
                                                   (200.0, 1200.0, 400.0), (50.0, 60.0, 10.0)])
def test_layer_column_is_peak_density_times_thickness(base, top, edge):
    # Closed form: peak (top - base), for sharp and raised-cosine edges alike (the ramp is
    # point-symmetric about each boundary). Reference: adaptive quadrature of density(h) with
    # the edges as breakpoints; tolerance 1e-9 (quadrature of smooth pieces).
    profile = UniformLayerProfile(base, top, 3.0, edge)
    points = [p for p in (base - edge / 2, base + edge / 2, top - edge / 2, top + edge / 2)
              if 0.0 < p < top + edge]
    integral, _ = quad(lambda h: float(profile.density(h)), 0.0, top + edge, points=points,
                       limit=200, epsabs=0.0, epsrel=1e-12)
    assert profile.column == 3.0 * (top - base)
    assert integral == pytest.approx(profile.column, rel=1e-9)


def test_layer_density_is_the_peak_inside_half_at_a_sharp_boundary_and_zero_outside():
    sharp = UniformLayerProfile(600.0, 1100.0, 2.0)
    np.testing.assert_array_equal(sharp.density([0.0, 599.0, 600.0, 850.0, 1100.0, 1101.0]),
                                  [0.0, 0.0, 1.0, 2.0, 1.0, 0.0])
    smooth = UniformLayerProfile(600.0, 1100.0, 2.0, edge_m=100.0)
    # raised cosine: 0 at boundary - w/2, half at the boundary, the peak at boundary + w/2
    np.testing.assert_allclose(smooth.density([550.0, 600.0, 650.0, 850.0, 1100.0, 1150.0]),
                               [0.0, 1.0, 2.0, 2.0, 1.0, 0.0], atol=1e-15)
    ground = UniformLayerProfile(0.0, 300.0, 2.0, edge_m=100.0)
    assert float(ground.density(0.0)) == 2.0  # a base on the ground stays sharp: all inside


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_layer_density_keeps_the_shape_of_the_altitudes(shape):
    altitudes = np.full(shape, 800.0)
    density = UniformLayerProfile(600.0, 1100.0, 1.0, 100.0).density(altitudes)
    assert density.shape == shape and np.all(density == 1.0)


@pytest.mark.parametrize(("base", "top", "edge"), [(-1.0, 100.0, 0.0), (100.0, 100.0, 0.0),
                                                   (0.0, 100.0, 150.0), (20.0, 100.0, 60.0)])
def test_layer_profile_refuses_layers_that_are_not_one(base, top, edge):
    with pytest.raises(InputError, match="needs 0 <= base < top"):
        UniformLayerProfile(base, top, 1.0, edge)


# --- the altitude levels ----------------------------------------------------------------------

def test_solver_levels_resolve_a_thin_layer_and_leave_other_atmospheres_alone(tmp_path):
    # A 300 m layer asks for 40 levels across it (7.5 m in a 100 km atmosphere); Earth without
    # layers keeps DEFAULT_PROFILE_LEVELS (so that its cached tables stay valid).
    fog = load_atmosphere(_config(tmp_path, "base_altitude_m = 0.0, top_altitude_m = 300.0"))
    profile = fog.optical_profile([550.0])
    assert profile.altitudes_m[1] - profile.altitudes_m[0] <= 300.0 / 40
    assert load_atmosphere("earth").profile_levels == DEFAULT_PROFILE_LEVELS


@pytest.mark.parametrize("edge_m", [5e-324, 1e-310, 1e-6])
def test_edges_finer_than_any_grid_ask_for_the_most_levels(tmp_path, edge_m):
    # An edge whose level spacing underflows to 0 (5e-324 / 10) or makes the level count
    # overflow (1e-310) was a ZeroDivisionError / OverflowError: it asks for the most levels
    # there are, like any edge finer than they resolve (1e-6 m).
    fine = load_atmosphere(_config(tmp_path, "base_altitude_m = 437.0, top_altitude_m = 563.0, "
                                             f"edge_m = {edge_m!r}"))
    assert fine.profile_levels == MAX_PROFILE_LEVELS


@pytest.mark.parametrize("n_levels", [None, 2001, 1001])
def test_sampled_layer_keeps_its_column_on_any_levels(tmp_path, n_levels):
    # Boundaries between levels (437 and 563 m are on neither 3.15 m nor 50 m nor 100 m levels):
    # the loader scales the sampled layer to its exact column, so the vertical optical depth is
    # 0.01 m^-1 x 126 m = 1.26 on every level grid (rounding only).
    atmosphere = load_atmosphere(_config(tmp_path, "base_altitude_m = 437.0, "
                                                   "top_altitude_m = 563.0"))
    profile = atmosphere.optical_profile([550.0], n_levels=n_levels)
    tau = np.trapezoid(profile.density[0], profile.altitudes_m) * profile.extinction_per_density[
        0, 0]
    assert tau == pytest.approx(0.01 * 126.0, rel=1e-12)


def test_levels_that_miss_a_layer_are_refused_naming_the_levels_it_needs(tmp_path):
    # 301 levels are 333 m apart: none lies in 437-563 m, the layer would vanish (was NaN).
    atmosphere = load_atmosphere(_config(tmp_path, "base_altitude_m = 437.0, "
                                                   "top_altitude_m = 563.0"))
    with pytest.raises(InputError, match=r"n_levels = 301 misses constituent 'cloud'.* "
                                         rf"n_levels >= {atmosphere.profile_levels}"):
        atmosphere.optical_profile([550.0], n_levels=301)


# --- the layer presets ------------------------------------------------------------------------

LAYER_PRESETS = [("earth-overcast", "cloud", 20.0, 550.0), ("earth-fog", "fog", 5.868, 550.0),
                 ("mars-dust-storm", "dust", 5.0, 880.0)]


@pytest.fixture(scope="module", params=LAYER_PRESETS, ids=[p[0] for p in LAYER_PRESETS])
def layer_preset(request):
    name, layer, tau, wavelength_nm = request.param
    atmosphere = load_atmosphere(name)
    profile = atmosphere.optical_profile([wavelength_nm], monochromatic=True)
    constituent = next(c for c in atmosphere.constituents if c.name == layer)
    return profile, profile.names.index(layer), constituent.profile, tau


def test_layer_preset_vertical_optical_depth_is_the_requested_one(layer_preset):
    # The optical depth the solvers' levels hold (trapezoid, as they interpolate linearly)
    # against the preset's optical_depth; rounding only.
    profile, index, _, tau = layer_preset
    column = np.trapezoid(profile.density[index], profile.altitudes_m)
    assert column * profile.extinction_per_density[index, 0] == pytest.approx(tau, rel=1e-10)


def test_layer_preset_column_along_rays_matches_the_continuous_profile(layer_preset):
    # Reference: the slant column of the preset's own continuous profile from the ground to the
    # top, trapezoid on 0.1 m steps near the ground plus adaptive quadrature above 20 km. Ours:
    # the ray marcher of the single-scattering and Monte Carlo solvers (`columns_along_segment`,
    # 256 samples, `ray_marched_transmittance`'s default) on the sampled levels, zenith cosines
    # 0.05-1. Measured worst: overcast -0.75 %, fog +0.22 %, storm +0.006 %; tolerance 1 %.
    profile, index, continuous, _ = layer_preset
    R, top = profile.bottom_radius_m, profile.top_radius_m
    h_step = profile.altitudes_m[1] - profile.altitudes_m[0]
    # the sampled layer is the continuous one times the loader's factor (its column to tau)
    peak = int(np.argmax(continuous.density(profile.altitudes_m)))
    scale = profile.density[index, peak] / float(continuous.density(profile.altitudes_m[peak]))
    density = np.ascontiguousarray(profile.density[index:index + 1])
    out = np.empty(1)
    for mu in np.linspace(0.05, 1.0, 8):
        d = _kernels.distance_to_top_boundary(R, mu, top)
        t = np.linspace(0.0, 20_000.0 / mu, 200_001)
        h = np.sqrt(R * R + t * t + 2.0 * R * mu * t) - R
        near = np.trapezoid(continuous.density(h), t)
        far, _ = quad(lambda s, mu=mu: float(continuous.density(
            math.sqrt(R * R + s * s + 2.0 * R * mu * s) - R)), t[-1], d, limit=200)
        _kernels.columns_along_segment(R, mu, 0.0, d, 256, R, h_step, density, out)
        assert out[0] == pytest.approx(scale * (near + far), rel=1 * PERCENT)


def test_fog_extinction_is_koschmieders_for_a_200_m_visibility():
    # Koschmieder (1924): extinction = 3.912 / visibility for a 2 % contrast threshold; the
    # preset's fog is V = 200 m at 550 nm. At 150 m (inside the fog, below its 100 m top edge)
    # the fog's own extinction. Its optical depth 5.868 is 3.912 / 200 m x 300 m exactly; what
    # is left is the trapezoid column of the sampled edge on 7.5 m levels, to which the loader
    # scales the layer: measured 8e-8; tolerance 1e-6.
    profile = load_atmosphere("earth-fog").optical_profile([550.0], monochromatic=True)
    index = profile.names.index("fog")
    density = np.interp(150.0, profile.altitudes_m, profile.density[index])
    extinction = density * profile.extinction_per_density[index, 0]
    assert extinction == pytest.approx(3.912 / 200.0, rel=1e-6)


# --- bad layers -------------------------------------------------------------------------------

@pytest.mark.parametrize(("layer", "key", "phrase"), [
    ("base_altitude_m = 1200.0, top_altitude_m = 1100.0", "density.top_altitude_m = 1100.0",
     "above base_altitude_m = 1200 m"),
    ("base_altitude_m = 1100.0, top_altitude_m = 1100.0", "density.top_altitude_m = 1100.0",
     "above base_altitude_m = 1100 m"),
    ("base_altitude_m = -100.0, top_altitude_m = 1100.0", "density.base_altitude_m = -100.0",
     ">= 0"),
    ("base_altitude_m = 600.0, top_altitude_m = 200_000.0", "density.top_altitude_m = 200000.0",
     "atmosphere.top_altitude_m = 100000 m"),
    ("base_altitude_m = 600.0, top_altitude_m = 1100.0, edge_m = 600.0", "density.edge_m = 600.0",
     "thickness"),
    ("base_altitude_m = 60.0, top_altitude_m = 1100.0, edge_m = 200.0", "density.edge_m = 200.0",
     "edge_m / 2 <= base_altitude_m = 60 m"),
    ("base_altitude_m = 600.0, top_altitude_m = 1100.0, edge_m = -5.0", "density.edge_m = -5.0",
     ">= 0"),
    ("base_altitude_m = 600.0, top_altitude_m = 1100.0, peak_density = -1.0",
     "density.peak_density = -1.0", ">= 0"),
    ("top_altitude_m = 1100.0", "density.base_altitude_m", "missing"),
    # 0.5 m levels at most in 100 km: a 0.2 m layer would fall between them
    ("base_altitude_m = 600.1, top_altitude_m = 600.3", "density.top_altitude_m = 600.3",
     ">= base_altitude_m + 1 m"),
])
def test_bad_layer_is_one_config_error_line_naming_the_key(tmp_path, layer, key, phrase):
    path = _config(tmp_path, layer)
    with pytest.raises(ConfigError) as info:
        load_atmosphere(path)
    message = str(info.value)
    assert message.startswith(f"{path}: constituent[0].{key}"), message
    assert phrase in message and "\n" not in message, message


def test_bad_layer_in_the_cli_exits_2_with_one_line_and_no_image(capsys, tmp_path):
    path = _config(tmp_path, "base_altitude_m = 1200.0, top_altitude_m = 1100.0")
    image = tmp_path / "x.png"
    code, _, err = run_cli(capsys, ["render", str(path), "--size", "8", "-o", str(image)])
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"skyscatter: {path}: constituent[0].density.top_altitude_m = 1100.0")
    assert not image.exists()
