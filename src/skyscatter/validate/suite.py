"""The validation suite of `skyscatter validate`: every case in order, the report, the verdict.

Cases (key: module):
- optical-depth      Rayleigh optical depth vs Bodhaine et al. 1999; ozone vs its cross-sections
- lut-vs-montecarlo  precomputed tables vs the Monte Carlo reference (Earth variants, Mars)
- disort             tables vs plane-parallel DISORT at small zenith angles
- cie-sky            luminance pattern vs CIE standard general skies 12 and 13
- spectrl2           ground irradiance and colour temperature vs SPECTRL2
- mars-pathfinder    Mars sky radiance along the almucantar, shapes of Meyran 2022's dust models
- mars-mer-colour    Mars daytime sky chromaticity vs MER Pancam (Bell et al. 2006)
- mars-mer-transmittance  Mars direct-sun transmittance at 880 nm vs MER (Lemmon et al. 2015)
- mars-blue-aureole  the blue glow around the setting sun on Mars (Ehlers et al. 2014)

Public names: `CASES`, `ValidationRun`, `run_suite`, `check_dependencies`.
"""

from __future__ import annotations

import importlib
import importlib.util
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from skyscatter.errors import InputError
from skyscatter.validate.report import CaseResult, ValidationSettings, write_report

__all__ = ["CASES", "ValidationRun", "check_dependencies", "run_suite"]

# key -> (module in skyscatter.validate, one line on what it checks)
CASES = {
    "optical-depth": ("optical_depth", "Rayleigh and ozone optical depth vs published values"),
    "lut-vs-montecarlo": ("lut_vs_montecarlo", "precomputed tables vs the Monte Carlo reference"),
    "disort": ("disort", "precomputed tables vs plane-parallel DISORT"),
    "cie-sky": ("cie_sky", "clear-sky luminance pattern vs CIE sky types 12 and 13"),
    "spectrl2": ("spectrl2", "ground irradiance and colour temperature vs SPECTRL2"),
    "mars-pathfinder": ("mars_pathfinder", "Mars sky radiance along the almucantar (Pathfinder)"),
    "mars-mer-colour": ("mars_mer_colour", "Mars daytime sky colour vs MER Pancam"),
    "mars-mer-transmittance": ("mars_mer_transmittance",
                               "Mars direct-sun transmittance at 880 nm vs MER"),
    "mars-blue-aureole": ("mars_blue_aureole", "Mars blue glow around the setting sun"),
}
# Third-party packages the cases need beyond skyscatter's own (the [validate] extra).
OPTIONAL_PACKAGES = {"matplotlib": "matplotlib", "pvlib": "pvlib",
                     "PythonicDISORT": "PythonicDISORT"}


@dataclass(frozen=True)
class ValidationRun:
    """The results of a run and where its report went."""

    results: list[CaseResult]
    report_path: Path
    summary_path: Path
    seconds: float

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)


def _run_case(key: str, settings: ValidationSettings) -> CaseResult:
    """One case (here or on a Dask worker)."""
    settings.log(f"[{key}] {CASES[key][1]}")
    return importlib.import_module(f"skyscatter.validate.{CASES[key][0]}").run(settings)


def _silent(message: str) -> None:
    """The log of a case on a worker: its lines are said where the results arrive."""


def _logged(settings: ValidationSettings, key: str, result: CaseResult) -> CaseResult:
    settings.log(f"[{key}] {CASES[key][1]}")
    return result


def check_dependencies() -> None:
    """Raise a one-line InputError naming the missing packages of the [validate] extra."""
    missing = [name for module, name in OPTIONAL_PACKAGES.items()
               if importlib.util.find_spec(module) is None]
    if missing:
        raise InputError(f"skyscatter validate needs {', '.join(missing)}: "
                         "pip install 'skyscatter[validate]'", key="dependencies",
                         value=missing)


def selected_cases(keys: Sequence[str] | None) -> list[str]:
    """The case keys to run, in suite order; an unknown key is an InputError."""
    if not keys:
        return list(CASES)
    for key in keys:
        if key not in CASES:
            raise InputError(f"unknown validation case {key!r}; choose from "
                             f"{', '.join(CASES)}", key="cases", value=key,
                             allowed=", ".join(CASES))
    return [key for key in CASES if key in keys]


def run_suite(settings: ValidationSettings, keys: Sequence[str] | None = None,
              on_case: Callable[[CaseResult], None] | None = None, *,
              client: Any = None) -> ValidationRun:
    """Run the cases `keys` (default: all), write the report and the JSON summary into
    `settings.output_dir`, and return the results; `on_case` sees each result as it ends.
    With `client` (a `distributed.Client`, `dask_cluster.dask_client`) the cases run at once
    on its workers, which write their figures into `settings.output_dir` (on another
    machine: a shared file system); their log lines are said here as each result arrives,
    in suite order."""
    check_dependencies()
    chosen = selected_cases(keys)
    Path(settings.output_dir).mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    if client is None:
        outcomes: Iterator[CaseResult] = (_run_case(key, settings) for key in chosen)
    else:
        remote = replace(settings, log=_silent)
        futures = [client.submit(_run_case, key, remote, pure=False) for key in chosen]
        outcomes = (_logged(settings, key, future.result())
                    for key, future in zip(chosen, futures, strict=True))
    results = []
    for result in outcomes:
        results.append(result)
        if on_case is not None:
            on_case(result)
    seconds = time.perf_counter() - start
    report, summary = write_report(results, settings, seconds)
    return ValidationRun(results, report, summary, seconds)
