"""`skyscatter completion bash|zsh|fish`: scripts the shells themselves accept and that complete
commands, choices and preset names; and `--quiet`, which leaves only errors on stderr."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from cli_runner import run_cli
from skyscatter import api
from skyscatter.cli import CAMERAS


def _script(capsys, shell: str) -> str:
    code, out, err = run_cli(capsys, ["completion", shell])
    assert code == 0 and err == ""
    return out


def _bash_complete(script: str, words: list[str]) -> list[str]:
    """What bash offers for the last of `words`, by calling the completion function as bash's
    programmable completion does (COMP_WORDS, COMP_CWORD)."""
    if shutil.which("bash") is None:
        pytest.skip("no bash")
    quoted = " ".join(f"'{word}'" for word in words)
    program = (f"{script}\nCOMP_WORDS=({quoted}); COMP_CWORD={len(words) - 1}; "
               "_skyscatter; printf '%s\\n' \"${COMPREPLY[@]}\"")
    result = subprocess.run(["bash", "-c", program], capture_output=True, text=True,
                            check=True, cwd="/")
    return [line for line in result.stdout.splitlines() if line]


def test_bash_accepts_the_script_and_completes(capsys):
    script = _script(capsys, "bash")
    if shutil.which("bash") is None:
        pytest.skip("no bash")
    registered = subprocess.run(["bash", "-c", f"{script}\ncomplete -p skyscatter"],
                                capture_output=True, text=True, check=True)
    assert registered.stdout.strip() == "complete -o filenames -F _skyscatter skyscatter"
    assert _bash_complete(script, ["skyscatter", "ren"]) == ["render"]
    assert _bash_complete(script, ["skyscatter", "--qu"]) == ["--quiet"]
    assert set(_bash_complete(script, ["skyscatter", "render", ""])) >= set(api.list_presets())
    assert _bash_complete(script, ["skyscatter", "render", "mars-p"]) == ["mars-physical"]
    assert _bash_complete(script, ["skyscatter", "-q", "render", "earth", "--camera", "pan"]) \
        == ["panorama"]
    assert _bash_complete(script, ["skyscatter", "render", "earth", "--camera", "pa"]) \
        == [camera for camera in CAMERAS if camera.startswith("pa")]
    assert _bash_complete(script, ["skyscatter", "render", "earth", "--sun-el"]) \
        == ["--sun-elevation"]
    assert _bash_complete(script, ["skyscatter", "cache", ""]) == ["list", "size", "clear"]
    assert _bash_complete(script, ["skyscatter", "render", "earth", "--size", ""]) == []


def test_zsh_runs_the_bash_function(capsys):
    """zsh runs the same function through bashcompinit, whose compgen does not filter by the
    typed word (zsh's compadd does that afterwards): the candidates are the commands, or an
    option's choices."""
    if shutil.which("zsh") is None:
        pytest.skip("no zsh")
    script = _script(capsys, "zsh")
    subprocess.run(["zsh", "-n"], input=script, text=True, check=True)

    def offered(words: list[str]) -> list[str]:
        program = (f"autoload -U compinit && compinit -u\n{script}\n"
                   f"COMP_WORDS=({' '.join(words)}); COMP_CWORD={len(words) - 1}; "
                   "_skyscatter; print -l -- \"${COMPREPLY[@]}\"")
        result = subprocess.run(["zsh", "-c", program], capture_output=True, text=True,
                                check=True, cwd="/")
        return result.stdout.split()

    assert "render" in offered(["skyscatter", "ren"])
    assert "render" not in offered(["skyscatter", "render", "ea"])
    assert "mars-physical" in offered(["skyscatter", "render", "ea"])
    assert offered(["skyscatter", "-q", "render", "earth", "--camera", "pa"]) == list(CAMERAS)


def test_fish_completes_from_its_script(capsys):
    if shutil.which("fish") is None:
        pytest.skip("no fish")
    script = _script(capsys, "fish")

    def offered(line: str) -> list[str]:
        result = subprocess.run(["fish", "-c", f"{script}\ncomplete -C '{line}'"],
                                capture_output=True, text=True, check=True, cwd="/")
        return [row.split("\t")[0] for row in result.stdout.splitlines()]

    assert offered("skyscatter ren") == ["render"]
    assert offered("skyscatter render mars-p") == ["mars-physical"]
    assert offered("skyscatter render earth --camera pan") == ["panorama"]
    assert "--quiet" in offered("skyscatter render earth --qu")


def test_an_unknown_shell_is_refused(capsys):
    code, _, err = run_cli(capsys, ["completion", "tcsh"])
    assert code == 2 and "invalid choice: 'tcsh'" in err


@pytest.mark.parametrize("where", ["before", "after"])
def test_quiet_leaves_only_errors(capsys, tmp_path, where):
    """-q before or after the command: a render prints nothing on stderr (no "wrote", no
    table note), its PNG is written; an error still prints its one line."""
    render = ["render", "earth", "--size", "8", "--wavelengths", "4", "-o",
              str(tmp_path / "sky.png")]
    argv = ["-q", *render] if where == "before" else [*render, "--quiet"]
    code, out, err = run_cli(capsys, argv)
    assert (code, out, err) == (0, "", "")
    assert (tmp_path / "sky.png").stat().st_size > 0
    code, _, err = run_cli(capsys, [*render[:-1], str(tmp_path / "sky.txt"), "-q"])
    assert code == 2 and err.count("\n") == 1 and "sky.txt" in err
    code, _, err = run_cli(capsys, render)  # without: the render says what it wrote
    assert code == 0 and "wrote" in err
