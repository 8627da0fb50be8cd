"""An own rule base in the closed loop: what the fuzzy-PI needs is checked first, said plainly."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.control.loop_rulebase import check_loop_rulebase, loop_problems
from fuzzkit.errors import ConfigError
from fuzzkit.formats.registry import load
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy.model import RuleBase, Term, Variable


def _scaled(var: Variable, factor: float) -> Variable:
    terms = tuple(Term(t.name, t.shape, tuple(p * factor for p in t.params)) for t in var.terms)
    return dataclasses.replace(var, low=var.low * factor, high=var.high * factor, terms=terms)


def _macvicar_on(factor: float) -> RuleBase:
    """MacVicar-Whelan with every universe multiplied by ``factor`` (names kept)."""
    rb = load("macvicar_whelan")
    return dataclasses.replace(
        rb,
        inputs=tuple(_scaled(v, factor) for v in rb.inputs),
        outputs=tuple(_scaled(v, factor) for v in rb.outputs),
    )


def _write(tmp_path: Path, rb: RuleBase, name: str = "own.yaml") -> str:
    path = tmp_path / name
    path.write_text(dump(rb), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "E1", "--rulebase", "temperature_pd"],
        ["compare", "E1", "--rulebase", "temperature_pd"],
        ["tune", "E1", "--rulebase", "temperature_pd", "--out", "never.yaml", "--quiet"],
    ],
)
def test_a_rule_base_with_other_variables_is_refused_with_what_the_loop_needs(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "rule base temperature_pd cannot run as the fuzzy-PI in the closed loop" in err
    assert "input e must be on [-1, 1] (the controller clips Ki*e to it), got [-20, 20]" in err
    assert "input de must be on [-1, 1] (the controller clips Kp*de to it), got [-2, 2]" in err
    assert "output power is a normalised correction (scaled by Kx): its range must contain 0" in err
    assert "got [0, 100]" in err
    assert "fix: rescale each universe to [-1, 1]" in err
    # never an option the command does not have (the table search's advice)
    assert "--tolerance" not in err and "--resolution" not in err


def test_a_rule_base_on_another_scale_is_refused_not_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path, _macvicar_on(100.0))
    assert main(["simulate", "E1", "--rulebase", path, "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no metrics: the run never started
    assert "input e must be on [-1, 1] (the controller clips Ki*e to it), got [-100, 100]" in (
        captured.err
    )
    assert "output du is a normalised correction" in captured.err
    assert "got [-100, 100]" in captured.err


def test_the_same_rule_base_rescaled_runs_within_the_safety_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # scaled up, then back down by the documented fix: the loop accepts it and the arm stays
    # far below the 25 N limit (the unscaled one reached 195 N before it was refused)
    rescaled = _macvicar_on(100.0)
    rescaled = dataclasses.replace(
        rescaled,
        inputs=tuple(_scaled(v, 0.01) for v in rescaled.inputs),
        outputs=tuple(_scaled(v, 0.01) for v in rescaled.outputs),
    )
    assert loop_problems(rescaled) == []
    path = _write(tmp_path, rescaled)
    assert main(["simulate", "E1", "--rulebase", path, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["tripped"] is False
    assert data["axes"]["z"]["peak_force_true"] < data["safety_limit"]


def test_names_and_order_are_free_but_the_count_is_not() -> None:
    rb = load("macvicar_whelan")
    swapped = dataclasses.replace(rb, inputs=rb.inputs[::-1])
    assert loop_problems(swapped) == []  # roles by position (or a spec's inputs:)
    renamed = dataclasses.replace(
        rb,
        inputs=tuple(
            dataclasses.replace(v, name=n) for v, n in zip(rb.inputs, ("a", "b"), strict=True)
        ),
        outputs=(dataclasses.replace(rb.outputs[0], name="delta_u"),),
    )
    assert loop_problems(renamed) == []
    one = dataclasses.replace(rb, inputs=rb.inputs[:1])
    with pytest.raises(
        ConfigError, match=r"exactly two inputs are needed .*got e \[-1, 1\]\n"
    ) as err:
        check_loop_rulebase(one, "one.yaml")
    assert "rescale" not in str(err.value)  # its universe is already the loop's
    two_out = dataclasses.replace(rb, outputs=rb.outputs * 2)
    with pytest.raises(ConfigError, match=r"exactly one output is needed, got du"):
        check_loop_rulebase(two_out, "two.yaml")


@pytest.mark.parametrize("name", ["macvicar_whelan", "paper_table1", "gaussian5", "sugeno_pi"])
def test_the_shipped_loop_rule_bases_pass(name: str) -> None:
    assert loop_problems(load(name)) == []


@pytest.mark.parametrize(
    ("low", "high", "fits"),
    [(-1.0, 1.0, True), (-2.0, 2.0, True), (-0.5, 1.0, True), (0.0, 1.0, True),
     (0.1, 1.0, False), (-2.5, 2.5, False), (-1.0, -0.1, False)],
)  # fmt: skip
def test_the_output_range_must_hold_zero_and_stay_normalised(
    low: float, high: float, fits: bool
) -> None:
    rb = load("macvicar_whelan")
    out = dataclasses.replace(rb.outputs[0], low=low, high=high)
    assert (loop_problems(dataclasses.replace(rb, outputs=(out,))) == []) is fits
