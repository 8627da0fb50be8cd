"""One syntax for one thing: latency, stiffness and figure options are spelled alike by every
command, every option's ``--help`` shows its default, and the docs use the spellings ``--help``
shows."""

from __future__ import annotations

import argparse
import re
import shlex

import pytest

from fuzzkit import units
from fuzzkit.cli import build_parser, main
from fuzzkit.errors import ConfigError
from tests._doc_commands import PAGES, commands


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


COMMANDS = _commands()


# ------------------------------------------------------------------ the parsers themselves


@pytest.mark.parametrize(
    "text, unit, n_per_m",
    [
        ("100", "N/mm", 1e5),
        ("100N/mm", "N/mm", 1e5),
        ("100 N/mm", "N/mm", 1e5),
        ("1e5N/m", "N/mm", 1e5),
        ("1e5 n/m", "N/mm", 1e5),
        ("100kN/m", "N/mm", 1e5),
        ("1e4", "N/m", 1e4),  # a scenario file's own unit
        ("10N/mm", "N/m", 1e4),
        ("0.5", "N/mm", 500.0),
    ],
)
def test_stiffness_is_read_with_or_without_its_unit(text: str, unit: str, n_per_m: float) -> None:
    assert units.parse_stiffness(text, unit) == pytest.approx(n_per_m, rel=1e-15)


@pytest.mark.parametrize(
    "text", ["", "abc", "100 N", "100N/mm/s", "0", "-5", "nan", "inf", "1e400", "10 lbf/in", "5,6"]
)
def test_a_bad_stiffness_names_the_spellings(text: str) -> None:
    with pytest.raises(ConfigError, match=r"100, 100N/mm, 1e5N/m"):
        units.parse_stiffness(text)


@pytest.mark.parametrize(
    "text, pairs",
    [
        ("0:0,2:1", [(0, 0), (2, 1)]),
        ("2:1", [(2, 1)]),
        ("2,1", [(2, 1)]),  # one pair written as simulate writes it
        ("0,0;2,1", [(0, 0), (2, 1)]),
        ("0,0 2,1", [(0, 0), (2, 1)]),
        ("0:0 2,1", [(0, 0), (2, 1)]),
    ],
)
def test_latency_lists_take_both_pair_spellings(text: str, pairs: list[tuple[int, int]]) -> None:
    assert units.parse_latencies(text) == pairs


@pytest.mark.parametrize("text", ["", "2", "0:0,2", "1:-1", "a:b", "1:2:3", "1.5:1", "0,0,2,1"])
def test_a_bad_latency_list_is_refused(text: str) -> None:
    with pytest.raises(ConfigError, match="SENSOR:COMMAND"):
        units.parse_latencies(text)


def test_one_latency_and_how_it_prints() -> None:
    assert units.parse_latency("3,3") == units.parse_latency("3:3") == (3, 3)
    assert units.parse_latency("3", sensor_only=True) == (3, None)
    with pytest.raises(ConfigError):
        units.parse_latency("3")
    assert units.latency_text((3, 1)) == "3:1"
    assert units.latencies_text([(0, 0), (3, 1)]) == "0:0,3:1"
    # what is printed reads back
    assert units.parse_latencies(units.latencies_text([(0, 0), (3, 1)])) == [(0, 0), (3, 1)]


# ------------------------------------------------------------------ every command alike


def _option(command: str, flag: str) -> argparse.Action:
    return next(a for a in COMMANDS[command]._actions if flag in a.option_strings)


LATENCY_COMMANDS = [
    name for name, p in COMMANDS.items() if any("--latency" in a.option_strings for a in p._actions)
]
STIFFNESS_COMMANDS = [
    name
    for name, p in COMMANDS.items()
    if any("--stiffness" in a.option_strings for a in p._actions)
]


def test_the_commands_that_take_a_latency_or_stiffness_are_found() -> None:
    assert {"simulate", "compare", "sweep", "tune", "stability"} <= set(LATENCY_COMMANDS)
    assert {"simulate", "sweep", "tune", "stability"} <= set(STIFFNESS_COMMANDS)


@pytest.mark.parametrize("command", LATENCY_COMMANDS)
def test_every_latency_option_takes_s_colon_c_and_s_comma_c(command: str) -> None:
    convert = _option(command, "--latency").type
    assert callable(convert)
    colon, comma = convert("3:1"), convert("3,1")
    assert colon == comma
    assert _option(command, "--latency").metavar.startswith("S:C")  # type: ignore[union-attr]


@pytest.mark.parametrize("command", STIFFNESS_COMMANDS)
def test_every_stiffness_option_takes_a_unit(command: str) -> None:
    convert = _option(command, "--stiffness").type
    assert callable(convert)
    plain, mm, m = (convert(t) for t in ("100", "100N/mm", "1e5N/m"))
    assert plain == mm == m
    assert float(plain if not isinstance(plain, list) else plain[0]) == 100.0  # N/mm inside


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "E1", "--latency", "1:x"],
        ["sweep", "E1", "--latency", "0:0,2", "--out", "r.csv"],
        ["stability", "regulate", "--stiffness", "10N/s", "--latency", "0:0"],
        ["tune", "E1", "--stiffness", "5,,10", "--out", "g.yaml"],
    ],
)
def test_a_bad_value_is_a_usage_error_naming_the_spellings(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert re.search(r"S:C|SENSOR:COMMAND|100N/mm", err), err


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_option_shows_its_default_in_help(name: str) -> None:
    """Walks every subcommand's parser: an option that takes a value says its default (or
    "none", or that it is required) in the text ``--help`` prints."""
    formatter = COMMANDS[name]._get_formatter()
    for action in COMMANDS[name]._actions:
        if not action.option_strings or action.nargs == 0 or action.help == argparse.SUPPRESS:
            continue
        text = formatter._get_help_string(action) or ""
        label = "/".join(action.option_strings)
        assert re.search(r"default|required", text, re.I), f"fuzzkit {name} {label}: {text!r}"
        # said once: not "(required) (default: none)" nor "required) (required)"
        assert not re.search(r"required\)\s*\((required|default)", text), f"{name} {label}"


def test_an_option_without_a_default_says_so() -> None:
    text = COMMANDS["simulate"].format_help()
    assert re.search(
        r"--rrd OUT\.rrd\s+write a Rerun recording of the run \(default:\s+none\)", text
    )
    assert "(required)" in COMMANDS["stability"].format_help()


# ------------------------------------------------------------------ --png is the figure


def test_plot_draws_with_png_and_keeps_out_as_an_alias(
    tmp_path: object, capsys: pytest.CaptureFixture[str]
) -> None:
    from pathlib import Path

    folder = Path(str(tmp_path))
    assert main(["plot", "macvicar_whelan", "--png", str(folder / "a.png")]) == 0
    assert main(["plot", "macvicar_whelan", "--out", str(folder / "b.png")]) == 0
    assert (folder / "a.png").read_bytes()[:4] == b"\x89PNG"
    assert (folder / "a.png").read_bytes() == (folder / "b.png").read_bytes()
    assert "--out" not in COMMANDS["plot"].format_help()  # the old spelling is not advertised
    capsys.readouterr()
    assert main(["plot", "macvicar_whelan"]) == 2
    assert "give --png" in capsys.readouterr().err


def test_sweep_names_its_figure_png_and_keeps_figure_as_an_alias() -> None:
    old = build_parser().parse_args(["sweep", "E1", "--out", "r.csv", "--figure", "f.png"])
    new = build_parser().parse_args(["sweep", "E1", "--out", "r.csv", "--png", "f.png"])
    assert old.png == new.png == "f.png"


# ------------------------------------------------------------------ the docs' spellings

_INLINE = re.compile(r"`(fuzzkit [a-z]+[^`]*)`")


def _doc_invocations() -> list[tuple[str, str]]:
    """``(where, command line)`` for every fuzzkit command of the docs: command blocks and
    inline code spans."""
    out = [(c.where, c.text) for page in PAGES for c in commands(page)]
    for page in PAGES:
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), start=1):
            for match in _INLINE.finditer(line):
                out.append((f"{page.name}:{number}", match.group(1)))
    return out


def _options_used(line: str) -> tuple[str | None, list[str]]:
    try:
        words = shlex.split(re.split(r"\s+(?:>|\||&&|;)\s*", line)[0])
    except ValueError:
        words = line.split()
    if len(words) < 2 or words[0] != "fuzzkit":
        return None, []
    return words[1], [w.split("=")[0] for w in words[2:] if re.match(r"^--?[a-zA-Z]", w)]


def test_the_docs_use_the_option_spellings_that_help_shows() -> None:
    seen = 0
    wrong = []
    for where, line in _doc_invocations():
        command, options = _options_used(line)
        if command not in COMMANDS:
            continue
        shown = COMMANDS[command].format_help()
        for option in options:
            seen += 1
            if not re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", shown):
                wrong.append(f"{where}: fuzzkit {command} {option} (not in its --help)")
    assert seen > 200, "the docs' commands were not found"
    assert not wrong, "\n".join(wrong)


def _choice_values(command: str, line: str) -> list[tuple[str, str]]:
    """``(option, value)`` for every option with choices that ``line`` gives a value."""
    try:
        words = shlex.split(re.split(r"\s+(?:>|\||&&|;)\s*", line)[0])
    except ValueError:
        words = line.split()
    choosers = {
        flag: action
        for action in COMMANDS[command]._actions
        if action.choices is not None and action.nargs != 0
        for flag in action.option_strings
    }
    out = []
    for i, word in enumerate(words):
        flag, eq, value = word.partition("=")
        if flag in choosers and (eq or i + 1 < len(words)):
            out.append((flag, value if eq else words[i + 1]))
    return out


def test_the_docs_give_options_with_choices_a_value_help_lists() -> None:
    # --loop auto (not a choice) was in docs/mujoco.md; --plant and --loop are the options
    # whose choices grew and shrank
    seen = set()
    wrong = []
    for where, line in _doc_invocations():
        command, _ = _options_used(line)
        if command not in COMMANDS:
            continue
        for option, value in _choice_values(command, line):
            action = next(a for a in COMMANDS[command]._actions if option in a.option_strings)
            seen.add(option)
            if value.isupper() or value.startswith(("{", "<", "$")):
                continue  # a placeholder, not a value
            if not set(value.split("|")) <= set(action.choices or ()):  # arm6|planar: either
                wrong.append(f"{where}: fuzzkit {command} {option} {value} (not a choice)")
    assert {"--loop", "--plant", "--controller"} <= seen
    assert not wrong, "\n".join(wrong)
    assert _choice_values("sweep", "fuzzkit sweep E1 --loop auto --plant=arm6") == [
        ("--loop", "auto"),
        ("--plant", "arm6"),
    ]


def test_every_plant_help_lists_every_registered_plant() -> None:
    from fuzzkit.loop.adapter import PLANTS

    commands = [n for n, c in COMMANDS.items() if "--plant" in c.format_help()]
    assert {"simulate", "compare", "sweep", "tune", "report", "stability"} <= set(commands)
    for name in commands:
        action = next(a for a in COMMANDS[name]._actions if "--plant" in a.option_strings)
        for plant, entry in PLANTS.items():
            assert f"{plant} ({entry.summary})" in (action.help or ""), (name, plant)


def test_the_check_of_doc_spellings_can_fail() -> None:
    command, options = _options_used("fuzzkit plot macvicar_whelan --out x.png")
    assert command == "plot" and options == ["--out"]
    assert not re.search(r"(?<![\w-])--out(?![\w-])", COMMANDS["plot"].format_help())


# ------------------------------------------------------------------ stiffness in scenario files


def _scenario_with(tmp_path: object, stiffness: str) -> str:
    from pathlib import Path

    from fuzzkit.studies.scenario_file import shipped_scenario_text

    text = shipped_scenario_text("E1")
    assert "stiffness_n_per_m: 10000.0," in text
    path = Path(str(tmp_path)) / "task.yaml"
    path.write_text(text.replace("stiffness_n_per_m: 10000.0,", f"stiffness_n_per_m: {stiffness},"))
    return str(path)


@pytest.mark.parametrize("value", ["10 N/mm", "10N/mm", "1e4 N/m", "10 kN/m", "10000.0", "1e4"])
def test_a_scenario_stiffness_takes_its_keys_unit_or_another_spelled_out(
    tmp_path: object, value: str
) -> None:
    from fuzzkit.studies.scenario_file import load_scenario

    exp = load_scenario(_scenario_with(tmp_path, value))
    assert exp.scenario.contact.stiffness_n_per_m == pytest.approx(1e4, rel=1e-15)


@pytest.mark.parametrize("value", ["10 lbf/in", "ten N/mm", "0 N/mm", "-5 N/m", "10 N"])
def test_a_bad_scenario_stiffness_is_refused_at_its_line(
    tmp_path: object, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _scenario_with(tmp_path, value)
    assert main(["validate", path]) == 2
    err = capsys.readouterr().err
    from pathlib import Path

    lines = Path(path).read_text(encoding="utf-8").splitlines()
    line = next(n for n, t in enumerate(lines, 1) if "stiffness_n_per_m" in t)
    assert re.search(rf"{re.escape(path)}:{line}:\d+: ", err), err
    assert "Traceback" not in err
