"""Rule tables are complete or say so (issue 28 item 5): every combination of input labels,
the label peaks and everything between, is checked for a rule that fires."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import registry, yaml_reader
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import Compound, Proposition, RuleBase, Term
from fuzzkit.fuzzy.rule_coverage import rule_gaps

PART = "{partition: triangular, labels: [N, Z, P]}"


def table(cells: str, default: str = "", terms: str = PART) -> str:
    return f"""\
name: hole
inputs:
  e: {{range: [-1, 1], terms: {terms}}}
  de: {{range: [-1, 1], terms: {PART}}}
outputs:
  du: {{range: [-1, 1]{default}, terms: {PART}}}
rules:
  table:
    rows: e
    columns: de
    output: du
    cells: |
""" + "".join(f"      {row}\n" for row in cells.split("/"))


def _dense_nan(rb: RuleBase, n: int = 201) -> set[tuple[float, float]]:
    """Independent reference: the points of a dense grid where no table rule's two memberships
    are both above zero (evaluated by the membership functions, not by supports)."""
    xs = np.linspace(-1.0, 1.0, n)
    e, de = rb.inputs
    mu_e = {t.name: evaluate_term(t, xs) for t in e.terms}
    mu_de = {t.name: evaluate_term(t, xs) for t in de.terms}
    fired = np.zeros((n, n), dtype=bool)
    for rule in rb.rules:
        assert isinstance(rule.antecedent, Compound)
        row, col = rule.antecedent.operands
        assert isinstance(row, Proposition) and isinstance(col, Proposition)
        fired |= np.minimum.outer(mu_e[row.term], mu_de[col.term]) > 0
    return {(float(xs[i]), float(xs[j])) for i, j in np.argwhere(~fired)}


def test_an_empty_cell_is_an_error_at_the_cell() -> None:
    text = table("N N Z/N Z -/Z P P")
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(text, "hole.yaml")
    (problem,) = info.value.problems
    # line 13 is the second row of cells; the '-' is its fifth character after the indent
    line = text.splitlines()[problem.location.line - 1]
    assert problem.location.line == 14 and line[problem.location.col - 1] == "-"
    assert "where e is Z and de is P" in problem.message and "NaN" in problem.message


def test_with_a_default_an_empty_cell_is_a_warning_and_eval_gives_the_default() -> None:
    text = table("N N Z/N Z -/Z P P", ", default: 0.25")
    rb, warnings = yaml_reader.loads_rulebase_with_warnings(text, "hole.yaml")
    (warning,) = warnings
    assert warning.severity == "warning" and warning.location.line == 14
    assert "where e is Z and de is P" in warning.message and "default 0.25" in warning.message
    y = evaluate(rb, {"e": np.array([0.0]), "de": np.array([1.0])})["du"]
    assert y[0] == 0.25


def test_every_empty_cell_is_reported_once() -> None:
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(table("- N Z/N Z -/Z P -"), "hole.yaml")
    cells = sorted(p.message.split(" (e.g.")[0] for p in info.value.problems)
    assert cells == [
        f"no rule fires for output 'du' where e is {r} and de is {c}"
        for r, c in (("N", "N"), ("P", "P"), ("Z", "P"))
    ]


@pytest.mark.parametrize(
    "terms",
    [
        # overlapping non-partition terms: Z is narrow, so between N and Z only N is active
        "{N: {shape: triangle, points: [-2, -1, 0.5]}, Z: {shape: triangle, points: [-0.2, 0, "
        "0.2]}, P: {shape: triangle, points: [-0.5, 1, 2]}}",
        # shoulders and a wide plateau
        "{N: {shape: left_shoulder, points: [-0.6, 0.1]}, Z: {shape: trapezoid, points: [-0.5, "
        "-0.1, 0.1, 0.5]}, P: {shape: right_shoulder, points: [-0.1, 0.6]}}",
        # Gaussians: every term active everywhere, so one rule per row covers all
        "{N: {shape: gaussian, mean: -1, sigma: 0.4}, Z: {shape: gaussian, mean: 0, sigma: 0.4},"
        " P: {shape: gaussian, mean: 1, sigma: 0.4}}",
    ],
)
@pytest.mark.parametrize("cells", ["N N Z/N Z -/Z P P", "- - -/N Z P/- - -", "N - -/- Z -/- - P"])
def test_the_check_agrees_with_a_dense_grid_of_the_engine(terms: str, cells: str) -> None:
    # the reference is independent of the check: the engine's own NaN on a 201 x 201 grid;
    # the check says "complete" exactly when the grid finds no NaN, and every grid NaN lies
    # in a reported cell
    with_default = yaml_reader.loads_rulebase(table(cells, ", default: 0", terms), "t.yaml")
    # without the default the engine gives NaN where nothing fires
    rb = dataclasses.replace(
        with_default, outputs=(dataclasses.replace(with_default.outputs[0], default=None),)
    )
    errors, _ = rule_gaps(rb)
    nan_at = _dense_nan(rb)
    assert (errors == []) == (nan_at == set()), (errors, sorted(nan_at)[:5])
    reported = {tuple(path[3:5]) for path, _ in errors}
    e, de = rb.inputs
    for x, y in nan_at:
        active_e = {t.name for t in e.terms if evaluate_mu(t, x) > 0}
        active_de = {t.name for t in de.terms if evaluate_mu(t, y) > 0}
        assert {(r, c) for r in active_e for c in active_de} <= reported, (x, y)


def evaluate_mu(term: Term, x: float) -> float:
    return float(evaluate_term(term, np.array([x]))[0])


def test_a_rule_list_gap_is_an_error_at_the_rules_block_with_the_combinations() -> None:
    text = """\
name: listed
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
  de: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  du: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
rules:
  - {if: {e: N}, then: {du: N}}
  - {if: {e: Z, de: {not: P}}, then: {du: Z}}
  - {if: {e: P}, then: {du: P}}
"""
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(text, "listed.yaml")
    (problem,) = info.value.problems
    assert problem.location.line == 8  # the rules block
    # 'not P' fires wherever mu_P < 1: only at de = 1 with e at Z's peak does nothing fire
    assert "where e is Z and de is P (e.g. at e=0, de=1)" in problem.message


def test_imported_files_get_their_own_located_warnings(tmp_path: Path) -> None:
    # imports get coverage: allow_gaps, so a combination no rule reaches is a located warning
    rb = registry.load("macvicar_whelan")
    sparse = dataclasses.replace(rb, rules=rb.rules[1:], table=None)
    path = tmp_path / "sparse.fll"
    path.write_text(registry.dumps(sparse, "fll", allow_loss=True))
    loaded, warnings = registry.load_with_warnings(path)
    assert loaded.coverage == "allow_gaps"
    (problem,) = [w for w in warnings if "no rule fires" in w.message]
    assert problem.severity == "warning"
    assert problem.location.file == str(path) and problem.location.line > 1
    assert "where e is NL and de is NL" in problem.message


def _transposed(cells: str, coverage: str = "") -> str:
    # rows are the second input (de), columns the first (e)
    return table(cells).replace("rows: e\n    columns: de", "rows: de\n    columns: e") + coverage


def test_a_hole_in_a_table_whose_rows_are_the_second_input_is_located_at_its_cell() -> None:
    text = _transposed("N N Z/N Z -/Z P P")
    assert "rows: de" in text
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(text, "hole.yaml")
    (problem,) = info.value.problems
    line = text.splitlines()[problem.location.line - 1]
    assert problem.location.line == 14 and line[problem.location.col - 1] == "-"
    # the hole is row Z (de), column P (e)
    assert "where e is P and de is Z" in problem.message


def test_allow_gaps_makes_an_empty_cell_a_located_warning_and_the_output_nan() -> None:
    text = table("N N Z/N Z -/Z P P") + "coverage: allow_gaps\n"
    rb, warnings = yaml_reader.loads_rulebase_with_warnings(text, "hole.yaml")
    (warning,) = warnings
    line = text.splitlines()[warning.location.line - 1]
    assert warning.severity == "warning" and warning.location.line == 14
    assert line[warning.location.col - 1] == "-" and "NaN" in warning.message
    assert np.isnan(evaluate(rb, {"e": np.array([0.0]), "de": np.array([1.0])})["du"][0])
