"""Every ``fuzzkit`` help text: examples that parse, help for every option, defaults shown."""

from __future__ import annotations

import argparse
import re
import shlex

import pytest

from fuzzkit.cli import build_parser


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


COMMANDS = sorted(_commands())


def _example_lines(help_text: str) -> list[str]:
    _, _, tail = help_text.partition("\nexample")
    return [ln.strip() for ln in tail.splitlines() if ln.strip().startswith("fuzzkit ")]


def test_the_known_commands_are_all_there() -> None:
    expected = {"validate", "info", "eval", "surface", "schema", "compile", "simulate"}
    assert expected | {"compare", "tune", "report", "demo"} <= set(COMMANDS)


@pytest.mark.parametrize("name", ["<top>", *COMMANDS])
def test_help_has_examples_that_parse(name: str) -> None:
    parser = build_parser() if name == "<top>" else _commands()[name]
    text = parser.format_help()
    lines = _example_lines(text)
    assert lines, f"fuzzkit {name} --help shows no example"
    commands = set()
    for line in lines:
        # drop shell redirections, chains and trailing remarks
        cmd = re.split(r"\s+(?:>|&&|\()", line)[0]
        argv = shlex.split(cmd)[1:]
        if "COMMAND" in argv:
            continue
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"example does not parse: {line!r} ({exc})")
        commands.add(args.command)
    assert name == "<top>" or name in commands, f"no example of fuzzkit {name} itself"


@pytest.mark.parametrize("name", COMMANDS)
def test_every_argument_has_help_and_every_default_is_shown(name: str) -> None:
    parser = _commands()[name]
    assert parser.description, f"fuzzkit {name} has no description"
    formatter = parser._get_formatter()
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        text = formatter._get_help_string(action) or ""
        label = "/".join(action.option_strings) or action.dest
        assert text.strip(), f"fuzzkit {name}: {label} has no help text"
        has_default = action.default not in (None, False, argparse.SUPPRESS)
        if has_default and action.nargs != 0:
            assert "default" in text.lower(), f"fuzzkit {name}: {label} hides its default"


@pytest.mark.parametrize(
    "name, option, shown",
    [
        ("simulate", "--controller", "(default: fuzzy-pi)"),
        ("simulate", "--plant", "(default: planar)"),
        ("simulate", "--seed", "(default: 0)"),
        ("report", "--plant", "(default: planar)"),
        ("report", "--seed", "(default: 0)"),
        ("report", "--workers", "(default: every core)"),
        ("demo", "--out", "(default: demo-out)"),
        ("compare", "--rulebase", "(default: macvicar_whelan)"),
    ],
)
def test_the_defaults_the_issue_names_are_in_the_help(name: str, option: str, shown: str) -> None:
    lines = _commands()[name].format_help().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"  {option} "))
    ends = (i for i in range(start + 1, len(lines)) if lines[i][:3] in ("  -", ""))
    end = next(ends, len(lines))  # the next option, or the blank line after the last one
    block = " ".join(" ".join(lines[start:end]).split())  # the option's own help, one line
    assert shown in block


def test_rule_base_help_names_every_readable_file_kind() -> None:
    from fuzzkit.cli import RULEBASE_SPEC_HELP
    from fuzzkit.formats import registry

    listed = set(re.findall(r"\.\w+", RULEBASE_SPEC_HELP))
    assert listed == set(registry.RULEBASE_SUFFIXES)


@pytest.mark.parametrize("name", COMMANDS)
def test_no_help_text_says_rule_bases_are_yaml_only(name: str) -> None:
    text = _commands()[name].format_help()
    assert ".yaml path" not in text and "YAML path" not in text
