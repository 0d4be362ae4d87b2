"""The public Python API refuses hostile arguments before any work with `InputError`, whose
one-line message names the argument (the same check and message the command line uses).

`render(sun_azimuth_deg=nan)` returned an image with 52 of 64 pixels NaN; `sky_radiance_rows`,
`viewpoint_at` and `sun_direction` passed NaN through. Allowed ranges are written here from the
physics (zenith angles 0-180 deg, latitudes -90-90, azimuths any finite number ...), not read
from the code. A table computation would show as a slow test; a private cache folder must
stay absent and no file may be written.
"""

import datetime
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skyscatter import api
from skyscatter.errors import InputError

EARTH = api.load_atmosphere("earth")
CAMERA = api.FisheyeCamera(8)
# A time-lapse's outputs (never written: every call below is refused first)
OUTPUTS = {"video_path": "x.mp4", "frames_dir": "frames"}
FINITE = (-math.inf, math.inf)


def _image() -> api.SkyImage:
    """A tiny 2 x 2 image on 3 wavelengths, made by hand (no rendering)."""
    wavelengths = np.array([450.0, 550.0, 650.0])
    return api.SkyImage(np.ones((2, 2, 3)), np.ones((2, 2), bool), np.ones((2, 2), bool),
                        wavelengths, np.ones(3))


def _observer() -> api.Observer:
    return api.make_observer("2024-06-21T21:30+02:00", 52.5, 13.4)


# name -> (call with the value, lowest allowed, highest allowed, lowest excluded)
SCALARS = {
    "sun_zenith_deg": (lambda v, o: api.render(EARTH, CAMERA, v, options=o), 0.0, 180.0, False),
    "sun_azimuth_deg": (lambda v, o: api.render(EARTH, CAMERA, 30.0, v, options=o), *FINITE,
                        False),
    "altitude_m": (lambda v, o: api.render(EARTH, CAMERA, 30.0, altitude_m=v, options=o), 0.0,
                   1e12, False),
    "orbit_latitude_deg": (lambda v, o: api.render(EARTH, CAMERA, 30.0, altitude_m=1e6,
                                                   orbit_latitude_deg=v, options=o),
                           -90.0, 90.0, False),
    "orbit_altitude_m": (lambda v, o: api.render_at(EARTH, CAMERA, _observer(),
                                                    orbit_altitude_m=v, options=o),
                         0.0, 1e12, False),
    "zenith_deg": (lambda v, o: api.sun_direction(v, 0.0), 0.0, 180.0, False),
    "azimuth_deg": (lambda v, o: api.sun_direction(30.0, v), *FINITE, False),
    "latitude_deg": (lambda v, o: api.make_observer("2024-06-21T12:00Z", v, 0.0), -90.0, 90.0,
                     False),
    "longitude_deg": (lambda v, o: api.make_observer("2024-06-21T12:00Z", 0.0, v), *FINITE,
                      False),
    "elevation_m": (lambda v, o: api.make_observer("2024-06-21T12:00Z", 0.0, 0.0, v), -500.0,
                    1e7, False),
    "planet_radius_m": (lambda v, o: api.viewpoint_at(0.0, v), 0.0, math.inf, True),
    "vertical_fov_deg": (lambda v, o: api.PerspectiveCamera(8, 8, v), 0.0,
                         math.nextafter(180.0, 0.0), True),
    "heading_deg": (lambda v, o: api.PerspectiveCamera(8, 8, 60.0, heading_deg=v), *FINITE,
                    False),
    "pitch_deg": (lambda v, o: api.PerspectiveCamera(8, 8, 60.0, pitch_deg=v), -90.0, 90.0,
                  False),
    "compensation_ev": (lambda v, o: api.save_image(_image(), compensation_ev=v), -40.0, 40.0,
                        False),
    "ev100": (lambda v, o: api.save_image(_image(), ev100=v), -40.0, 40.0, False),
}
# name -> (call with the list, lowest allowed, highest allowed)
LISTS = {
    "sun_zeniths_deg": (lambda v, o: api.sky_radiance_rows(EARTH, v, [0.0], [0.0], [550.0],
                                                           options=o), 0.0, 180.0),
    "view_zeniths_deg": (lambda v, o: api.sky_radiance_rows(EARTH, [30.0], v, [0.0], [550.0],
                                                            options=o), 0.0, 180.0),
    "relative_azimuths_deg": (lambda v, o: api.sky_radiance_rows(EARTH, [30.0], [0.0], v,
                                                                 [550.0], options=o), *FINITE),
    "wavelengths_nm": (lambda v, o: api.sky_radiance_rows(EARTH, [30.0], [0.0], [0.0], v,
                                                          options=o), 280.5, 1690.0),
}
# name -> (call with the value, lowest allowed, highest allowed)
WHOLE = {
    "size": (lambda v, o: api.FisheyeCamera(v), 1, 2**20),
    "width": (lambda v, o: api.PerspectiveCamera(v, 8, 60.0), 1, 2**20),
    "orders": (lambda v, o: api.solver_options(EARTH, orders=v, use_cache=False), 1, 1000),
    "n_samples": (lambda v, o: api.solver_options(EARTH, n_samples=v, use_cache=False), 1,
                  10**9),
}


def _inside(value, low, high, low_open=False) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return math.isfinite(value) and (value > low if low_open else value >= low) and value <= high


hostile_number = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 1e13, -1e13]),
    st.floats(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.text(max_size=8),  # "30" as text is refused too: the API takes numbers
    st.booleans(),
    st.lists(st.floats(), max_size=2),
    st.just(None),
    st.just(object()),
)


@pytest.fixture
def options(tmp_path, monkeypatch):
    """Solver options whose cache lives in tmp_path/cache, which must stay absent."""
    monkeypatch.chdir(tmp_path)
    return api.solver_options(EARTH, orders=2, n_samples=8, cache_dir=tmp_path / "cache")


def _refused(call, name):
    with pytest.raises(InputError) as raised:
        call()
    message = str(raised.value)
    assert "\n" not in message
    assert name in message or name == raised.value.key
    return message


SETTINGS = settings(max_examples=80, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(name=st.sampled_from(sorted(SCALARS)), value=hostile_number)
def test_a_number_outside_its_range_raises_input_error_naming_it(options, tmp_path, name, value):
    call, low, high, low_open = SCALARS[name]
    if _inside(value, low, high, low_open) or (value is None and name in ("ev100",
                                                                          "orbit_altitude_m",
                                                                          "orbit_latitude_deg")):
        return  # allowed: not this test's business
    _refused(lambda: call(value, options), name)
    assert list(tmp_path.iterdir()) == []


@SETTINGS
@given(name=st.sampled_from(sorted(LISTS)), good=st.lists(st.just(550.0), max_size=2),
       value=hostile_number)
def test_a_list_with_one_bad_element_raises_input_error_naming_it(options, tmp_path, name, good,
                                                                  value):
    call, low, high = LISTS[name]
    if _inside(value, low, high):
        value = math.nan
    if name.startswith(("sun", "view")):
        good = [30.0 for _ in good]
    _refused(lambda: call([*good, value], options), name)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", sorted(LISTS))
def test_an_empty_list_raises_input_error_naming_it(options, tmp_path, name):
    _refused(lambda: LISTS[name][0]([], options), name)
    assert list(tmp_path.iterdir()) == []


@SETTINGS
@given(name=st.sampled_from(sorted(WHOLE)), value=hostile_number)
def test_a_whole_number_outside_its_range_raises_input_error_naming_it(options, tmp_path, name,
                                                                       value):
    call, low, high = WHOLE[name]
    if isinstance(value, int) and not isinstance(value, bool) and low <= value <= high:
        return
    if value is None and name == "orders":
        return  # None: the config's orders
    _refused(lambda: call(value, options), name)


@pytest.mark.parametrize(("call", "name"), [
    (lambda o: api.render("earth", CAMERA, 30.0, options=o), "atmosphere"),
    (lambda o: api.render(EARTH, "fisheye", 30.0, options=o), "camera"),
    (lambda o: api.render_at(EARTH, CAMERA, "Berlin", options=o), "observer"),
    (lambda o: api.save_image("sky", ev100=0.0), "image"),
    (lambda o: api.make_observer("0001-01-01T00:00+05:00", 0.0, 0.0), "time"),
    (lambda o: api.make_observer(datetime.datetime(9999, 12, 31, 23, tzinfo=datetime.timezone(
        datetime.timedelta(hours=-5))), 0.0, 0.0), "time"),
    (lambda o: api.make_observer("MSD inf", 0.0, 0.0), "Mars Sol Date"),
    (lambda o: api.render(EARTH, api.FisheyeCamera(100_000), 30.0, options=o), "memory"),
    (lambda o: api.render(EARTH, CAMERA, 30.0, wavelengths_nm=[200.0, 550.0], options=o),
     "wavelengths_nm"),
    (lambda o: api.load_solver(EARTH, [900.0], options=o), "wavelengths_nm"),
    (lambda o: api.sky_radiance_rows(EARTH, [30.0], [0.0], [0.0], [2000.0], options=o),
     "wavelengths_nm"),
    (lambda o: api.sky_radiance_rows(EARTH, [30.0], list(np.linspace(0, 90, 100)),
                                     list(range(100)), [550.0], solver="montecarlo",
                                     options=api.solver_options(EARTH, orders=2, n_samples=10**6,
                                                                use_cache=False)),
     "samples"),
    (lambda o: api.timelapse(EARTH, CAMERA, [datetime.datetime(2024, 1, 1, tzinfo=datetime.UTC)],
                             0.0, 0.0, **OUTPUTS, compensation_ev=math.nan, options=o),
     "compensation_ev"),
    (lambda o: api.timelapse(EARTH, CAMERA, [datetime.datetime(2024, 1, 1, tzinfo=datetime.UTC)],
                             0.0, 0.0, **OUTPUTS, adaptation_time_s=-1.0, options=o),
     "adaptation_time_s"),
    (lambda o: api.timelapse(EARTH, CAMERA, [datetime.datetime(2024, 1, 1, tzinfo=datetime.UTC)],
                             0.0, 0.0, **OUTPUTS, fps=math.nan, options=o), "fps"),
    (lambda o: api.timelapse(EARTH, CAMERA, [], 0.0, 0.0, **OUTPUTS, options=o),
     "time-lapse"),
    (lambda o: api.look_at_direction(api.viewpoint_at(1e6, 6.4e6, 0.0, 0.0), 0.0, math.inf,
                                     0.0, 6.4e6), "target_longitude_deg"),
    (lambda o: api.orbit_field_of_view_deg(math.nan, 6.4e6), "altitude_m"),
])
def test_wrong_types_and_impossible_requests_raise_input_error(options, tmp_path, call, name):
    _refused(lambda: call(options), name)
    assert list(tmp_path.iterdir()) == []


def test_render_with_nan_sun_azimuth_is_refused_not_drawn(options):
    # The report's case: an image with 52 of 64 pixels NaN came back.
    message = _refused(lambda: api.render(EARTH, CAMERA, 30.0, math.nan, options=options),
                       "sun_azimuth_deg")
    assert message == "sun_azimuth_deg = nan is not allowed: a finite number"


def test_render_cost_estimate_says_gib_and_the_way_past_it():
    with pytest.raises(InputError) as raised:
        api.check_render_cost(api.PerspectiveCamera(2**20, 2**20, 60.0))
    message = str(raised.value)
    # 2^40 pixels x (32 x 16 + 512) B = 1024 TiB
    assert "about 1,048,576 GiB" in message and "allow_large=True" in message
    api.check_render_cost(api.PerspectiveCamera(2**20, 2**20, 60.0), allow_large=True)


@pytest.mark.parametrize(("field", "value"), [
    ("operator", "sepia"), ("operator", ["aces"]), ("colour_space", "cmyk"),
    ("colour_space", None), ("exr_content", "depth"), ("ev100", math.nan),
    ("compensation_ev", 41.0)])
def test_image_options_refuse_unknown_names_and_exposures_when_made(field, value):
    _refused(lambda: api.ImageOptions(**{field: value}), field)
    _refused(lambda: api.save_image(_image(), **{"ev100": 0.0, field: value}), field)


def test_image_options_accept_every_name_the_tone_curves_and_colour_spaces_accept():
    # Membership in the tables must agree with what the curves and matrices run on: each
    # accepted name works in tonemap / xyz_to_rgb (colour spaces in any case, as xyz_to_rgb).
    from skyscatter.render.tonemap import OPERATORS, tonemap
    from skyscatter.spectrum.colour import RGB_SPACES, xyz_to_rgb
    for operator in OPERATORS:
        api.ImageOptions(operator=operator)
        assert np.isfinite(tonemap(np.ones(3), operator)).all()
    for space in [*RGB_SPACES, "SRGB", "Display-P3"]:
        api.ImageOptions(colour_space=space)
        assert np.isfinite(xyz_to_rgb(np.ones(3), space)).all()


def test_save_image_with_options_writes_the_same_bytes_as_with_its_parameters(tmp_path):
    image = _image()
    chosen = dict(ev100=2.5, compensation_ev=-0.5, operator="reinhard",
                  colour_space="display-p3", balance_to_light=True, exr_content="luminance")
    ev_plain = api.save_image(image, tmp_path / "a.png", tmp_path / "a.exr", **chosen)
    ev_options = api.save_image(image, tmp_path / "b.png", tmp_path / "b.exr",
                                options=api.ImageOptions(**chosen))
    assert ev_plain == ev_options == 2.5
    for suffix in ("png", "exr"):
        assert (tmp_path / f"a.{suffix}").read_bytes() == (tmp_path / f"b.{suffix}").read_bytes()
    _refused(lambda: api.save_image(image, tmp_path / "c.png", options={"ev100": 1.0}),
             "options")
