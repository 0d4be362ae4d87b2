"""Run a catalogue of careless and hostile command lines and config files through `skyscatter` and
count, per class, how each ended: refused with one clear line, an internal error or traceback,
silent nonsense (exit 0 with NaN, zeros or a wrong file), or killed by the time/memory limit.

    python scripts/probe_bad_inputs.py [--json results.json] [--only CLASS]

Each case runs `python -m skyscatter.cli` in a fresh temporary folder with a private table cache,
a 12 GiB address-space limit and a 120 s time limit. To probe another tree (e.g. an older commit
checked out in a worktree), set PYTHONPATH=/that/tree/src. Slow: a few minutes on 2 cores, since
some bad inputs are only refused (or not) after tables were computed.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

FAST = ["--solver", "single", "--samples", "16", "--size", "16", "--wavelengths", "3"]
RADIANCE = ["radiance", "earth", "--sun-zenith", "30", "--view-zenith", "10",
            "--view-azimuth", "0", "--solver", "single", "--samples", "16"]
TIME_LIMIT_S = 120
MEMORY_LIMIT = 12 * 2**30


@dataclass
class Result:
    code: int
    stdout: str
    stderr: str
    folder: Path
    timed_out: bool = False


@dataclass
class Case:
    group: str
    name: str
    argv: list[str]
    files: dict[str, bytes] = field(default_factory=dict)  # written into the folder first
    mentions: str = ""  # a refusal's message must name this (the option or key), if given
    # Result -> None when the outcome is right, else the class of what went wrong
    judge: Callable[[Result], str | None] | None = None


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run(case: Case, cache: Path) -> Result:
    folder = Path(tempfile.mkdtemp(prefix="probe-"))
    for name, data in case.files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    env = dict(os.environ, SKYSCATTER_CACHE_DIR=str(cache))
    try:
        done = subprocess.run([sys.executable, "-m", "skyscatter.cli", *case.argv], cwd=folder,
                              env=env, capture_output=True, timeout=TIME_LIMIT_S,
                              preexec_fn=_limit_memory, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as expired:
        return Result(-1, (expired.stdout or b"").decode(errors="replace"),
                      (expired.stderr or b"").decode(errors="replace"), folder, True)
    return Result(done.returncode, done.stdout.decode(errors="replace"),
                  done.stderr.decode(errors="replace"), folder)


def _new_files(result: Result, inputs: dict[str, bytes]) -> list[str]:
    return sorted(str(p.relative_to(result.folder)) for p in result.folder.rglob("*")
                  if p.is_file() and str(p.relative_to(result.folder)) not in inputs)


def _messages(result: Result) -> list[str]:
    """The message lines of stderr (argparse's usage block left out)."""
    return [line for line in result.stderr.splitlines()
            if line.startswith("skyscatter") and "error" in line or
            line.startswith("skyscatter:")]


def refused(case: Case) -> Callable[[Result], str | None]:
    """The right outcome: exit 2, one message line, no traceback, no file written."""

    def judge(result: Result) -> str | None:
        if result.timed_out or result.code < 0 or result.code == 137:
            return "killed (time or memory)"
        if "Traceback" in result.stderr or "internal error" in result.stderr or result.code == 1:
            return "internal error"
        if result.code == 0:
            return "accepted: nonsense output, exit 0"
        messages = _messages(result)
        if result.code != 2 or len(messages) != 1:
            return f"unclear (exit {result.code}, {len(messages)} message lines)"
        if "precomputing" in result.stderr or "wrote" in result.stderr:
            return "refused only after the work"
        if case.mentions.lower() not in messages[0].lower():
            return "misleading message"
        if _new_files(result, case.files):
            return "refused but left files"
        return None

    return judge


def strict_json(result: Result) -> str | None:
    """Right: strict JSON on stdout (no bare NaN or Infinity), or a clear refusal."""
    if result.code == 2 and "Traceback" not in result.stderr and len(_messages(result)) == 1:
        return None
    if result.code != 0:
        return f"failed (exit {result.code})"
    try:
        json.loads(result.stdout, parse_constant=lambda name: (_ for _ in ()).throw(
            ValueError(name)))
    except ValueError as error:
        return f"not strict JSON ({error})"
    return None


def rendered(result: Result) -> str | None:
    """Right: a valid input that must work (exit 0, the image written, no NaN)."""
    if "Traceback" in result.stderr or "internal error" in result.stderr:
        return "internal error"
    if result.code != 0 or not (result.folder / "sky.png").exists():
        return f"failed (exit {result.code})"
    return None


def jpeg_written(result: Result) -> str | None:
    path = result.folder / "x.jpg"
    if result.code == 2 and not path.exists():
        return None  # refused clearly: also right
    if result.code != 0 or not path.exists():
        return f"failed (exit {result.code})"
    return None if path.read_bytes()[:3] == b"\xff\xd8\xff" else "PNG bytes under .jpg"


def png_on_stdout(result: Result) -> str | None:
    if (result.folder / "-").exists():
        return "wrote a file named '-'"
    if result.code != 0:
        return f"failed (exit {result.code})"
    return None  # stdout is decoded text here; the file check is what matters


PRESET = Path(__file__).resolve().parents[1] / "src/skyscatter/atmosphere/presets/exo-dense-n2.toml"


def _preset_with(old: str, new: str) -> bytes:
    text = PRESET.read_text()
    assert old in text, old
    return text.replace(old, new).encode()


def catalogue() -> list[Case]:
    render = ["render", "earth", *FAST]
    cases = [
        # 1. non-finite and out-of-range numbers on the command line
        *(Case("cli numbers", f"--view-azimuth {value}", [*RADIANCE[:7], value, *RADIANCE[8:]],
               mentions="azimuth") for value in ("nan", "inf")),
        *(Case("cli numbers", " ".join(extra), [*render, *extra], mentions=mention)
          for extra, mention in (
            (["--camera", "perspective", "--aspect", "0"], "aspect"),
            (["--camera", "perspective", "--aspect", "nan"], "aspect"),
            (["--camera", "perspective", "--aspect", "-1"], "aspect"),
            (["--sun-azimuth", "nan"], "azimuth"), (["--sun-azimuth", "inf"], "azimuth"),
            (["--sun-elevation", "nan"], "sun"),
            (["--camera", "perspective", "--fov", "0"], "fov"),
            (["--camera", "perspective", "--fov", "nan"], "fov"),
            (["--camera", "perspective", "--heading", "nan"], "heading"),
            (["--camera", "perspective", "--pitch", "inf"], "pitch"),
            (["--exposure", "nan"], "exposure"), (["--exposure-compensation", "inf"], "comp"),
            (["--twinkle", "-1", "--time", "2024-06-21T22:00+02:00", "--lat", "52", "--lon",
              "13"], "twinkle"),
            (["--lat", "nan", "--time", "2024-06-21T12:00Z", "--lon", "0"], "lat"),
            (["--elevation-m", "nan"], "elevation"), (["--elevation-m=-1e9"], "elevation"),
            (["--terrain", "demo", "--terrain-spacing", "0"], "spacing"),
            (["--camera", "orbit", "--distance-km", "nan"], "distance"),
            (["--magnitude-limit", "nan", "--time", "2024-06-21T23:00+02:00", "--lat", "52",
              "--lon", "13"], "magnitude"))),
        Case("cli numbers", "timelapse --step infh",
             ["timelapse", "earth", "--start", "2024-06-21T20:00Z", "--end",
              "2024-06-21T21:00Z", "--step", "infh", "--lat", "52", "--lon", "13", *FAST],
             mentions="step"),
        Case("cli numbers", "timelapse --fps nan",
             ["timelapse", "earth", "--start", "2024-06-21T20:00Z", "--end",
              "2024-06-21T21:00Z", "--frames", "2", "--fps", "nan", "--lat", "52", "--lon",
              "13", *FAST], mentions="fps"),
        # 2. sizes and costs
        Case("sizes and costs", "--size 100000", [*render[:-4], "--wavelengths", "3",
                                                  "--size", "100000"]),
        Case("sizes and costs", "--aspect 1e9",
             [*render, "--camera", "perspective", "--aspect", "1e9"]),
        Case("sizes and costs", "--orders 100000",
             ["precompute", "earth", "--orders", "100000", "--wavelengths", "3"]),
        Case("sizes and costs", "--samples 10**12",
             [*RADIANCE[:-4], "--solver", "montecarlo", "--samples", "1000000000000"]),
        # 3. wavelengths outside the data
        Case("wavelengths", "radiance --wavelengths 200", [*RADIANCE, "--wavelengths", "200"]),
        Case("wavelengths", "radiance --wavelengths 1e-300",
             [*RADIANCE, "--wavelengths", "1e-300"]),
        Case("wavelengths", "render --wavelengths 1e9,",
             ["render", "earth", "--solver", "single", "--size", "16", "--wavelengths", "1e9,"]),
        Case("wavelengths", "radiance --wavelengths 5000", [*RADIANCE, "--wavelengths", "5000"]),
        # 4. internal errors
        Case("internal errors", "binary config", [*RADIANCE[:1], "bad.toml", *RADIANCE[2:]],
             {"bad.toml": bytes(range(256)) * 4}),
        Case("internal errors", "UTF-16 config", [*RADIANCE[:1], "bad.toml", *RADIANCE[2:]],
             {"bad.toml": '[planet]\npreset = "earth"\n'.encode("utf-16")}),
        Case("internal errors", "deeply nested TOML", [*RADIANCE[:1], "bad.toml", *RADIANCE[2:]],
             {"bad.toml": b"a = " + b"[" * 5000 + b"]" * 5000 + b"\n"}),
        Case("internal errors", "--time year 0 in UTC",
             [*render, "--time", "0001-01-01T01:00+05:00", "--lat", "0", "--lon", "0"]),
        Case("internal errors", "--time year 10000 in UTC",
             [*render, "--time", "9999-12-31T23:00-05:00", "--lat", "0", "--lon", "0"]),
        Case("internal errors", "montecarlo at the top of the atmosphere",
             ["render", "earth", "--solver", "montecarlo", "--samples", "2", "--size", "8",
              "--wavelengths", "3", "--elevation-m", "100000"], judge=rendered),
        # 5. machine-readable output
        Case("strict JSON", "radiance nan azimuth --format json",
             [*RADIANCE[:7], "nan", *RADIANCE[8:], "--format", "json", "--wavelengths", "550,"],
             judge=strict_json),
        Case("strict JSON", "radiance montecarlo --format json",
             [*RADIANCE[:-4], "--solver", "montecarlo", "--samples", "64", "--format", "json",
              "--wavelengths", "550,"], judge=strict_json),
        Case("strict JSON", "radiance at the top of the atmosphere --format json",
             [*RADIANCE, "--altitude", "100000", "--format", "json", "--wavelengths", "550,"],
             judge=strict_json),
        Case("strict JSON", "radiance 200 nm --format json",
             [*RADIANCE, "--format", "json", "--wavelengths", "200"], judge=strict_json),
        # 6. outputs
        Case("outputs", "-o x.jpg", [*render, "-o", "x.jpg"], judge=jpeg_written),
        Case("outputs", "-o -", [*render, "-o", "-"], judge=png_on_stdout),
        Case("outputs", "-o into a missing folder's file", [*render, "-o", "a_file/x.png"],
             {"a_file": b"not a folder"}),
        Case("outputs", "-o is a folder", [*render, "-o", "out"], {"out/keep": b""}),
        Case("outputs", "--exr into a file's 'folder'",
             [*render, "-o", "x.png", "--exr", "a_file/x.exr"], {"a_file": b"not a folder"}),
        Case("outputs", "--cache-dir is a file",
             ["precompute", "earth", "--wavelengths", "3", "--orders", "1", "--cache-dir",
              "a_file"], {"a_file": b"not a folder"}),
        # 7. config values
        Case("config values", "surface_density_kg_m3 = 1e308",
             [*RADIANCE[:1], "bad.toml", *RADIANCE[2:]],
             {"bad.toml": _preset_with("surface_pressure_pa = 500_000.0",
                                       "surface_density_kg_m3 = 1e308")},
             mentions="surface_density_kg_m3"),
        Case("config values", "planet radius 1e30",
             [*RADIANCE[:1], "bad.toml", *RADIANCE[2:]],
             {"bad.toml": _preset_with("radius_m = 6_371_000.0", "radius_m = 1e30")},
             mentions="radius_m"),
    ]
    for case in cases:
        case.judge = case.judge or refused(case)
    return cases


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None, help="write every result here")
    parser.add_argument("--only", default=None, help="run one class")
    args = parser.parse_args()
    cache = Path(tempfile.mkdtemp(prefix="probe-cache-"))
    counts: dict[str, Counter] = {}
    rows = []
    for case in catalogue():
        if args.only and case.group != args.only:
            continue
        result = run(case, cache)
        verdict = case.judge(result) or "right"
        counts.setdefault(case.group, Counter())[verdict] += 1
        last = (result.stderr.strip().splitlines() or [""])[-1][:150]
        rows.append({"class": case.group, "case": case.name, "verdict": verdict,
                     "exit": result.code, "stderr_last_line": last})
        print(f"{case.group:16} {case.name:45} {verdict:35} {last}", flush=True)
    print("\nclass             right / cases   what went wrong")
    for group, counter in counts.items():
        wrong = ", ".join(f"{n} {v}" for v, n in counter.items() if v != "right")
        print(f"{group:16} {counter['right']:>5} / {sum(counter.values()):<5}   {wrong}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
