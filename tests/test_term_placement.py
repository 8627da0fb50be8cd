"""Terms that do not fit their range (issue 29 item 7): wholly outside is an error at the term,
a shoulder that never reaches 1 inside the range a warning at its points."""

from __future__ import annotations

import pytest

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import yaml_reader

DOC = """\
name: place
inputs:
  e:
    range: [-1, 1]
    terms:
      N: {{shape: left_shoulder, points: [{n}, 0]}}
      Z: {{shape: triangle, points: [-1, 0, 1]}}
      P: {{shape: right_shoulder, points: [0, {p}]}}
{extra}outputs:
  du:
    range: [-1, 1]
    terms: {{partition: triangular, labels: [N, Z, P]}}
rules:
  - {{if: {{e: N}}, then: {{du: N}}}}
  - {{if: {{e: Z}}, then: {{du: Z}}}}
  - {{if: {{e: P}}, then: {{du: P}}}}
"""


@pytest.mark.parametrize(
    ("n", "p", "line", "name", "where"),
    [
        ("-1.5", "1", 6, "N", "membership 1 at -1.5) ends before the range starts"),
        ("-1", "1.25", 8, "P", "membership 1 at 1.25) starts after the range ends"),
    ],
)
def test_a_shoulder_that_never_reaches_1_is_a_warning_at_the_term(
    n: str, p: str, line: int, name: str, where: str
) -> None:
    text = DOC.format(n=n, p=p, extra="")
    _, warnings = yaml_reader.loads_rulebase_with_warnings(text, "place.yaml")
    (warning,) = warnings
    assert warning.location.line == line and f"shoulder {name!r} never reaches 1" in warning.message
    assert where in warning.message
    assert text.splitlines()[line - 1][warning.location.col - 1 :].startswith("[")  # its points


@pytest.mark.parametrize("n, p", [("-1", "1"), ("-0.5", "0.5"), ("-2", "2")])
def test_shoulders_reaching_1_inside_the_range_or_beyond_it_both_ways(n: str, p: str) -> None:
    # a plateau that reaches into the range is fine; one cut short on both sides warns twice
    _, warnings = yaml_reader.loads_rulebase_with_warnings(DOC.format(n=n, p=p, extra=""), "x")
    assert len(warnings) == (2 if n == "-2" else 0)


@pytest.mark.parametrize(
    "term",
    [
        "{shape: triangle, points: [2, 3, 4]}",
        "{shape: triangle, points: [1, 2, 3]}",  # 0 at its foot 1, the range's end
        "{shape: trapezoid, points: [-5, -4, -3, -1]}",
        "{shape: singleton, value: 7}",
    ],
)
def test_a_term_wholly_outside_its_range_is_an_error_at_that_term(term: str) -> None:
    extra = f"      X: {term}\n"
    text = DOC.format(n="-1", p="1", extra=extra).replace(
        "  - {if: {e: P}, then: {du: P}}\n",
        "  - {if: {e: P}, then: {du: P}}\n  - {if: {e: X}, then: {du: P}}\n",
    )
    with pytest.raises(RuleBaseError) as info:
        yaml_reader.loads_rulebase(text, "place.yaml")
    (problem,) = info.value.problems
    assert (
        problem.location.line == 9 and "term 'X' lies wholly outside the range" in problem.message
    )


def test_a_term_touching_the_range_at_one_point_is_inside() -> None:
    # a triangle whose peak is the range's end has membership 1 there
    extra = "      X: {shape: triangle, points: [1, 1, 3]}\n"
    rb = yaml_reader.loads_rulebase(DOC.format(n="-1", p="1", extra=extra), "place.yaml")
    assert "X" in rb.inputs[0].term_names
