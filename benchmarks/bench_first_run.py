"""Benchmark: what a new user waits for, from a fresh install to the first picture (issue 18).

Each step runs `skyscatter` in a fresh process with an empty numba cache (NUMBA_CACHE_DIR in a
new temporary folder, so no kernel compiled earlier on this machine is reused) and an empty
table cache, in this order:

1. the first render without `skyscatter compile` (kernels compiled on the way: the install
   before issue 18, and a `pip install` whose user skipped the step);
2. `skyscatter compile` on a fresh kernel cache (what `make` now runs at install time);
3. the first render after it (kernels from the cache, tables computed), `--repeat` times, each
   with a new table cache;
4. the same render again (kernels and tables from the cache).

Prints wall and CPU time (user + system of the child, all its threads) of each step.

Run: python benchmarks/bench_first_run.py [--render-args "earth --size 512"]
"""

from __future__ import annotations

import argparse
import os
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def timed(command: list[str], environment: dict[str, str]) -> tuple[float, float]:
    """(wall [s], CPU of the child [s]) of running `command` to completion."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, env=environment, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--render-args", default="earth",
                        help="the first render's arguments (default: earth, every default)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="first renders after the install step, each with a new table "
                             "cache (default 3: the machine's noise beside the number)")
    args = parser.parse_args()
    skyscatter = [sys.executable, "-m", "skyscatter.cli"]
    with tempfile.TemporaryDirectory(prefix="bench-first-run-") as folder:
        work = Path(folder)

        def environment(kernels: str) -> dict[str, str]:
            return {**os.environ, "NUMBA_CACHE_DIR": str(work / kernels)}

        def render(kernels: str, tables: str) -> list[str]:
            return [*skyscatter, "render", *shlex.split(args.render_args), "-o",
                    str(work / "sky.png"), "--cache-dir", str(work / tables)]

        def again(k: int) -> str:
            return f" (again, new table cache {k + 1})" if k else ""

        steps = [
            ("first render, kernels compiled on the way", render("kernels-a", "tables-a"),
             environment("kernels-a")),
            ("skyscatter compile (install step)", [*skyscatter, "compile"],
             environment("kernels-b")),
            *[(f"first render after `skyscatter compile`{again(k)}",
               render("kernels-b", f"tables-b{k}"), environment("kernels-b"))
              for k in range(args.repeat)],
            ("the same render again (tables cached)", render("kernels-b", "tables-b0"),
             environment("kernels-b")),
        ]
        print(f"render: skyscatter render {args.render_args}")
        print("| step | wall [s] | CPU [s] |")
        print("|---|---|---|")
        for label, command, env in steps:
            wall, cpu = timed(command, env)
            print(f"| {label} | {wall:.1f} | {cpu:.1f} |", flush=True)


if __name__ == "__main__":
    main()
