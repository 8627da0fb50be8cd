"""Every numeric option of every command refuses a bad value at the option: exit 2, the
option named, before any work (fuzzkit.cli.numbers, fuzzkit.cli.units).

The options are found from the parser, so a new numeric option is walked without being
listed here; one declared with a bare ``int`` or ``float`` fails the first test.
"""

from __future__ import annotations

import argparse

import pytest

from fuzzkit.cli import build_parser, main, numbers
from fuzzkit.cli import units as cli_units

#: Values no numeric option takes: negative, huge, not finite, not a number.
ALWAYS_BAD = ("-1", "-0.5", "1e308", str(10**30), "nan", "NaN", "inf", "-inf", "abc", "")
#: Options for which 0 is a value: a seed, and the one-number latency (the sensor delay
#: alone, 0 periods); every other refuses it (a count, a fraction, a stiffness, a pair S:C).
ZERO_TAKEN = {"--seed", "simulate--latency", "compare--latency"}


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


COMMANDS = _commands()


def _numeric(action: argparse.Action) -> bool:
    return isinstance(action.type, numbers.Number) or action.type in cli_units.OPTION_TYPES


OPTIONS = [
    (name, action.option_strings[0])
    for name, command in COMMANDS.items()
    for action in command._actions
    if action.option_strings and _numeric(action)
]


def test_the_walk_finds_the_numeric_options() -> None:
    found = set(OPTIONS)
    for expected in [
        ("simulate", "--seed"),
        ("simulate", "--stiffness"),
        ("compare", "--latency"),
        ("tune", "--budget"),
        ("sweep", "--duration"),
        ("eval", "--rules"),
        ("surface", "--resolution"),
        ("compile", "--tolerance"),
        ("stability", "--contact-sector"),
    ]:
        assert expected in found
    assert len(found) >= 30


def test_no_option_takes_a_bare_int_or_float() -> None:
    bare = [
        (name, a.option_strings or a.dest)
        for name, command in COMMANDS.items()
        for a in command._actions
        if a.type in (int, float)
    ]
    assert bare == [], "declare numeric options with fuzzkit.cli.numbers"


def _refusal(command: str, option: str, value: str, capsys: pytest.CaptureFixture[str]) -> str:
    """argparse's error for ``command option=value`` (empty when the value was taken)."""
    try:
        # the value is converted as the option is read: a bad one stops argparse there,
        # before it asks for the command's required arguments (whose absence exits too)
        COMMANDS[command].parse_args([f"{option}={value}"])
    except SystemExit as exc:
        assert exc.code == 2
    err = capsys.readouterr().err
    return err if f"argument {option}" in err else ""


@pytest.mark.parametrize(("command", "option"), OPTIONS, ids=[f"{c}{o}" for c, o in OPTIONS])
def test_bad_values_are_refused_at_the_option(
    command: str, option: str, capsys: pytest.CaptureFixture[str]
) -> None:
    for value in ALWAYS_BAD:
        err = _refusal(command, option, value, capsys)
        assert err, f"{command} {option} {value!r} was taken"
        assert "expected" in err and "Traceback" not in err
    zero = _refusal(command, option, "0", capsys)
    taken = option in ZERO_TAKEN or f"{command}{option}" in ZERO_TAKEN
    assert bool(zero) != taken, (command, option, zero)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["simulate", "E1", "--seed", "-1"], "argument --seed: expected an integer from 0 to"),
        (["sweep", "E1", "--out", "x.csv", "--duration", "nan"], "argument --duration"),
        (["simulate", "E1", "--latency", "99999999999999999:0"], "integers 0 to 1000"),
        (["simulate", "E1", "--stiffness", "1e12"], "from 0.1 N/mm to 10000 N/mm"),
        (["tune", "E1", "--out", "g.yaml", "--stiffness", "5,1e9"], "'1e9'"),
        (
            ["compile", "macvicar_whelan", "--target", "c", "--out", "o", "--max-bytes", "0"],
            "from 1 to",
        ),
    ],
)
def test_the_command_exits_2_with_the_option_named(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "internal error" not in err


def test_ranges_are_the_limits_of_the_code_they_feed() -> None:
    from fuzzkit.codegen.lookup_table import MAX_BREAKPOINTS, MIN_BREAKPOINTS
    from fuzzkit.control.spec_reader import MAX_SAMPLES
    from fuzzkit.fuzzy.rule_view import MAX_RULES
    from fuzzkit.viz.surface import MAX_RESOLUTION

    assert (numbers.RULES_DRAWN.low, numbers.RULES_DRAWN.high) == (1, MAX_RULES)
    assert numbers.SURFACE_RESOLUTION.high == MAX_RESOLUTION
    # a spec's safety.watchdog.periods takes 1 (the semantic checks) to MAX_SAMPLES
    assert (numbers.WATCHDOG_PERIODS.low, numbers.WATCHDOG_PERIODS.high) == (1, MAX_SAMPLES)
    assert (numbers.BREAKPOINTS.low, numbers.BREAKPOINTS.high) == (
        MIN_BREAKPOINTS,
        MAX_BREAKPOINTS,
    )


def test_in_range_values_are_taken_as_numbers() -> None:
    assert numbers.SEED("7") == 7 and isinstance(numbers.SEED("7"), int)
    assert numbers.DURATION_S("2.5") == 2.5
    assert numbers.UNIT_FRACTION("1") == 1.0
    with pytest.raises(argparse.ArgumentTypeError, match=r"integer from 1 to 1024, got '1.5'"):
        numbers.WORKERS("1.5")
    with pytest.raises(argparse.ArgumentTypeError, match=r"number in \(0, 1\], got '0'"):
        numbers.UNIT_FRACTION("0")
