"""Shell completion scripts for the command line, generated from its argparse parser
(`skyscatter completion bash|zsh|fish`).

The parser is the one source: its commands, their options, which options take a value and
their `choices`, and its positionals. Words argparse cannot know (the preset names, the
solvers, the cloud presets) come in `values`, keyed by the argument's `dest`. An argument
typed `Path`, or whose metavar says FILE or IMAGE, and a positional without `choices` (a
preset or a config file) also complete file names; a number completes nothing.

bash uses `complete -F` (bash manual, "Programmable Completion"); zsh runs the same function
through its bash emulation (`bashcompinit`, zsh manual "Completion System"); fish gets one
`complete -c` line per word (fish manual, "complete").
"""

from __future__ import annotations

import argparse
import shlex
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["SHELLS", "completion_script"]

SHELLS = ("bash", "zsh", "fish")


@dataclass
class _Option:
    names: list[str]  # "-o", "--output"
    takes_value: bool
    words: list[str]  # the values to offer
    files: bool  # file names too


@dataclass
class _Command:
    name: str
    help: str
    options: list[_Option] = field(default_factory=list)
    words: list[str] = field(default_factory=list)  # the positionals' values
    files: bool = False  # a positional takes a file name


def _words(action: argparse.Action, values: Mapping[str, Sequence[str]]) -> list[str]:
    if action.choices is not None:
        return [str(choice) for choice in action.choices]
    return [str(word) for word in values.get(action.dest, ())]


def _files(action: argparse.Action) -> bool:
    metavar = str(action.metavar or "")
    return action.type is Path or "FILE" in metavar or "IMAGE" in metavar


def _command(name: str, help_text: str, parser: argparse.ArgumentParser,
             values: Mapping[str, Sequence[str]]) -> _Command:
    command = _Command(name, help_text)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        if action.option_strings:
            command.options.append(_Option(list(action.option_strings), action.nargs != 0,
                                           _words(action, values), _files(action)))
        else:
            words = _words(action, values)
            command.words += words
            command.files |= action.choices is None
    return command


def _model(parser: argparse.ArgumentParser, values: Mapping[str, Sequence[str]]
           ) -> tuple[_Command, list[_Command]]:
    """The parser itself (its options) and its commands."""
    top = _command("", "", parser, values)
    commands = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            commands += [_command(name, helps.get(name, ""), sub, values)
                         for name, sub in action.choices.items()]
    return top, commands


def _compgen(words: Sequence[str]) -> str:
    return f'COMPREPLY=($(compgen -W {shlex.quote(" ".join(words))} -- "$cur"))'


def _bash_case(command: _Command) -> list[str]:
    """The lines completing the words after `command`."""
    lines = ['            case "$prev" in']
    for option in command.options:
        if option.takes_value:
            reply = _compgen(option.words) if option.words else "COMPREPLY=()"
            if option.files:
                reply += '; COMPREPLY+=($(compgen -f -- "$cur"))'
            lines.append(f"                {'|'.join(option.names)}) {reply}; return ;;")
    lines += ["            esac",
              '            if [[ $cur == -* ]]; then '
              f"{_compgen(sorted(n for o in command.options for n in o.names))}; return; fi",
              f"            {_compgen(command.words)}"]
    if command.files:
        lines.append('            COMPREPLY+=($(compgen -f -- "$cur"))')
    return lines


def _bash(prog: str, top: _Command, commands: list[_Command]) -> str:
    function = "_" + prog.replace("-", "_")
    lines = [f"{function}() {{",
             "    # slices index from 0 in bash and zsh alike (zsh's arrays start at 1)",
             '    local cur="${COMP_WORDS[@]:$COMP_CWORD:1}" '
             'prev="${COMP_WORDS[@]:$((COMP_CWORD - 1)):1}"',
             '    local command="" word i',
             "    for ((i = 1; i < COMP_CWORD; i++)); do  # the first word not an option",
             '        word="${COMP_WORDS[@]:$i:1}"',
             '        if [[ -z $command && $word != -* ]]; then command=$word; fi',
             "    done",
             '    case "$command" in',
             '        "")',
             '            if [[ $cur == -* ]]; then '
             f"{_compgen(sorted(n for o in top.options for n in o.names))}; return; fi",
             f"            {_compgen([c.name for c in commands])}",
             "            ;;"]
    for command in commands:
        lines += [f"        {command.name})", *_bash_case(command), "            ;;"]
    lines += ["    esac", "}", f"complete -o filenames -F {function} {prog}", ""]
    return "\n".join(lines)


def _fish_quote(text: str) -> str:
    return "'" + text.replace("\\", "\\\\").replace("'", "\\'") + "'"


def _fish_option(prog: str, condition: str, option: _Option) -> str:
    flags = " ".join(f"-l {name[2:]}" if name.startswith("--") else f"-s {name[1:]}"
                     for name in option.names)
    line = f"complete -c {prog} -n {_fish_quote(condition)} {flags}"
    if option.takes_value:
        line += " -r -F" if option.files else " -x"
        if option.words:
            line += f" -a {_fish_quote(' '.join(option.words))}"
    return line


def _fish(prog: str, top: _Command, commands: list[_Command]) -> str:
    lines = [f"complete -c {prog} -f"]  # no file names unless an argument takes one
    lines += [_fish_option(prog, "__fish_use_subcommand", option) for option in top.options]
    for command in commands:
        lines.append(f"complete -c {prog} -n __fish_use_subcommand -a {command.name} "
                     f"-d {_fish_quote(command.help)}")
        seen = f"__fish_seen_subcommand_from {command.name}"
        lines += [_fish_option(prog, seen, option) for option in command.options]
        if command.words:
            lines.append(f"complete -c {prog} -n {_fish_quote(seen)} "
                         f"-a {_fish_quote(' '.join(command.words))}")
        if command.files:
            lines.append(f"complete -c {prog} -n {_fish_quote(seen)} -F")
    return "\n".join(lines) + "\n"


def completion_script(parser: argparse.ArgumentParser, shell: str, *,
                      values: Mapping[str, Sequence[str]]) -> str:
    """The completion script for `shell` (one of `SHELLS`) of `parser`'s program; `values`
    maps an argument's dest to the words to offer for it where it has no `choices`."""
    top, commands = _model(parser, values)
    prog = parser.prog
    header = (f"# {shell} completion for {prog}, generated from its parser by "
              f"`{prog} completion {shell}`\n")
    if shell == "bash":
        return header + f"# use: source <({prog} completion bash)\n" + _bash(prog, top, commands)
    if shell == "zsh":
        return (header + f"# use, after compinit: source <({prog} completion zsh)\n"
                "autoload -U +X bashcompinit && bashcompinit\n" + _bash(prog, top, commands))
    if shell == "fish":
        return (header + f"# use: {prog} completion fish > ~/.config/fish/completions/"
                f"{prog}.fish\n" + _fish(prog, top, commands))
    raise ValueError(f"no completion for the shell {shell!r}; one of {', '.join(SHELLS)}")
