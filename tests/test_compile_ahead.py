"""`skyscatter compile` and the first-run note (skyscatter.compile_ahead)."""

import numpy as np
import pytest

from cli_runner import run_cli
from skyscatter import compile_ahead
from skyscatter.cli import build_parser
from skyscatter.render.camera import PerspectiveCamera
from skyscatter.render.scene import ground_viewpoint, sun_direction
from skyscatter.render.terrain import EARTH_RADIUS_M, HORIZON_MIN_RAYS, demo_mountains
from skyscatter.transport.lut_solver import (
    AERIAL_GRID_MIN_POINTS,
    SKY_GRID_EXACT_DEG,
    SKY_GRID_MIN_RAYS,
    SUN_GRID_MIN_RAYS,
)


@pytest.fixture
def fresh_marker(tmp_path, monkeypatch):
    """A machine whose kernels were never compiled: no marker yet."""
    marker = tmp_path / "numba" / "compiled"
    monkeypatch.setattr(compile_ahead, "marker_path", lambda: marker)
    return marker


def test_the_first_run_announces_the_compilation_and_later_runs_do_not(capsys, fresh_marker):
    arguments = ["radiance", "earth", "--sun-zenith", "30", "--wavelengths", "550"]
    code, out, err = run_cli(capsys, arguments)
    assert code == 0 and out
    assert err.splitlines()[0] == compile_ahead.FIRST_RUN_NOTE
    assert fresh_marker.is_file()
    code, _, err = run_cli(capsys, arguments)
    assert code == 0 and compile_ahead.FIRST_RUN_NOTE not in err


def test_a_failed_run_leaves_the_note_for_the_next_one(capsys, fresh_marker):
    code, _, err = run_cli(capsys, ["radiance", "no-such-preset", "--sun-zenith", "30"])
    assert code == 2 and compile_ahead.FIRST_RUN_NOTE in err
    assert not fresh_marker.exists()


def test_commands_that_compile_nothing_say_nothing(capsys, fresh_marker):
    code, _, err = run_cli(capsys, ["presets"])
    assert code == 0 and err == "" and not fresh_marker.exists()


def test_every_warm_up_command_is_a_valid_command_line():
    parser = build_parser()
    for _, arguments in compile_ahead.WARM_UP_COMMANDS:
        output = ["-o", "x.png"] if arguments[0] == "render" else []
        args = parser.parse_args([*arguments, *output, "--cache-dir", "x"])
        assert args.command in {"render", "radiance"}


def test_the_warm_up_reaches_the_full_frame_kernels():
    # the sky-view grid and the aureole's per-frame table compile only in frames of at least
    # SKY_GRID_MIN_RAYS rays from one observer: the panorama's sky half must have that many
    panorama = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                    if "panorama" in arguments)
    size = int(panorama[panorama.index("--size") + 1])
    assert size * (2 * size) // 2 >= SKY_GRID_MIN_RAYS


def test_the_warm_up_reaches_the_sun_grid():
    # the sun grid compiles only in frames with at least SUN_GRID_MIN_RAYS rays within
    # SKY_GRID_EXACT_DEG of the sun: the perspective frame centred on it must have them (its
    # camera and sun as the command line parses them; the sun 30 deg high by default)
    command = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                   if "sun grid" in what)
    args = build_parser().parse_args(list(command))
    assert args.sun_zenith is None and args.sun_elevation is None
    camera = PerspectiveCamera(round(args.size * args.aspect), args.size, args.fov,
                               heading_deg=args.heading, pitch_deg=args.pitch)
    directions, _ = camera.directions()
    sun = sun_direction(60.0, args.sun_azimuth)
    near = directions.reshape(-1, 3) @ sun > np.cos(np.radians(SKY_GRID_EXACT_DEG))
    assert np.count_nonzero(near) >= SUN_GRID_MIN_RAYS
    assert directions.shape[0] * directions.shape[1] >= SKY_GRID_MIN_RAYS


def test_the_warm_up_reaches_the_low_sun_and_the_terrain_horizon():
    # the marched single scattering of a low sun compiles in a full frame's sky-view grid with
    # the sun near the horizon; the terrain's horizon culling only in frames of at least
    # HORIZON_MIN_RAYS rays (make run's scenes have both)
    parser = build_parser()
    low_sun = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                   if "low sun" in what)
    args = parser.parse_args([*low_sun, "-o", "x.png"])
    assert args.camera == "panorama" and args.sun_elevation <= 5.0
    assert args.size * (2 * args.size) // 2 >= SKY_GRID_MIN_RAYS
    terrain = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                   if "terrain" in what)
    args = parser.parse_args([*terrain, "-o", "x.png"])
    # every pixel of the perspective camera is a ray
    assert args.terrain == "demo" and args.camera == "perspective"
    assert round(args.size * args.aspect) * args.size >= HORIZON_MIN_RAYS


def test_the_warm_up_terrain_frame_takes_the_aerial_perspective_grid():
    # the grid's kernels compile only for frames with AERIAL_GRID_MIN_POINTS rays on the
    # terrain: the warm-up's own camera and mountains, intersected
    terrain_command = next(arguments for what, arguments in compile_ahead.WARM_UP_COMMANDS
                           if "terrain" in what)
    args = build_parser().parse_args([*terrain_command, "-o", "x.png"])
    camera = PerspectiveCamera(round(args.size * args.aspect), args.size, args.fov or 60.0,
                               heading_deg=args.heading, pitch_deg=args.pitch)
    viewpoint = ground_viewpoint(args.altitude, EARTH_RADIUS_M)
    mountains = demo_mountains(peak_m=args.terrain_height, spacing_m=args.terrain_spacing,
                               planet_radius_m=EARTH_RADIUS_M)
    directions, _ = camera.directions()
    rays = np.ascontiguousarray(viewpoint.direction_to_world(directions).reshape(-1, 3))
    *_, hit = mountains.intersect(np.asarray(viewpoint.position_m, dtype=float), rays)
    assert np.count_nonzero(hit) >= AERIAL_GRID_MIN_POINTS


def test_compile_runs_the_warm_up_and_writes_the_marker(capsys, fresh_marker, monkeypatch):
    # two of the commands (the rest are the same command line with other cameras and presets;
    # all of them run in `make`'s install step, whose failure stops the build)
    commands = compile_ahead.WARM_UP_COMMANDS
    monkeypatch.setattr(compile_ahead, "WARM_UP_COMMANDS", (commands[0], commands[-1]))
    code, out, err = run_cli(capsys, ["compile"])
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("compiled 1/2: tables and the fisheye (")
    assert lines[1].startswith("compiled 2/2: radiance (")
    assert lines[2].startswith("compiled in ") and err == ""
    assert fresh_marker.is_file()


def test_a_failing_warm_up_command_is_reported_with_its_message(capsys, fresh_marker,
                                                                 monkeypatch):
    monkeypatch.setattr(compile_ahead, "WARM_UP_COMMANDS",
                        (("a typo", ("render", "no-such-preset", "--size", "16")),))
    code, _, err = run_cli(capsys, ["compile"])
    assert code == 2
    assert "compiling the kernels failed in `skyscatter render no-such-preset --size 16`" in err
    assert "no-such-preset" in err.split("(exit code 2):")[1]
    assert not fresh_marker.exists()
