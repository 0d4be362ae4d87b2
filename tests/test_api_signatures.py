"""The public API's calling contract: no function in `api.__all__` takes more than
`MAX_POSITIONAL` positional parameters; the rest are keyword-only, so a call names its options
(`render(atmosphere, camera, 60.0, wavelengths_nm=..., options=...)`) and options can be added
or reordered without silently shifting a caller's arguments."""

import datetime
import inspect

import pytest

from skyscatter import api
from skyscatter.errors import InputError

MAX_POSITIONAL = 5


def positional_count(function) -> int:
    """The parameters of `function` that a caller may pass by position (not *args)."""
    kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    return sum(p.kind in kinds for p in inspect.signature(function).parameters.values())


PUBLIC_FUNCTIONS = sorted(name for name in api.__all__
                          if inspect.isfunction(getattr(api, name)))


def test_the_count_sees_positional_and_keyword_only_parameters():
    def six(a, b, c, d, e, f=1, *, g=2): ...

    def five(a, b, /, c, d=1, e=2, *args, f=3, **kwargs): ...

    assert positional_count(six) == 6
    assert positional_count(five) == 5


def test_the_facade_has_its_functions():
    assert {"render", "render_at", "timelapse", "save_image", "sky_radiance_rows",
            "solver_options", "demo_mountains", "viewer_server"} <= set(PUBLIC_FUNCTIONS)


@pytest.mark.parametrize("name", PUBLIC_FUNCTIONS)
def test_no_public_function_takes_more_than_five_positional_parameters(name):
    count = positional_count(getattr(api, name))
    assert count <= MAX_POSITIONAL, (
        f"api.{name} takes {count} positional parameters: make those after the first "
        f"{MAX_POSITIONAL} keyword-only (*)")


def test_options_after_the_leading_ones_cannot_be_passed_by_position():
    with pytest.raises(TypeError):
        api.render(api.load_atmosphere("earth"), api.FisheyeCamera(8), 30.0, 180.0, 0.0,
                   [550.0])


WHEN = [datetime.datetime(2024, 1, 1, tzinfo=datetime.UTC)]


@pytest.mark.parametrize("image, key", [
    (api.ImageOptions(ev100=10.0), "ev100"),  # a time-lapse meters each frame itself
    ("aces", "image"),
])
def test_timelapse_refuses_image_options_it_cannot_follow_before_any_work(tmp_path, image, key):
    with pytest.raises(InputError) as raised:
        api.timelapse(api.load_atmosphere("earth"), api.FisheyeCamera(8), WHEN, 0.0, 0.0,
                      video_path=tmp_path / "x.mp4", frames_dir=tmp_path / "frames",
                      image=image)
    assert raised.value.key == key
    assert list(tmp_path.iterdir()) == []
