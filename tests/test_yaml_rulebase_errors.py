"""Malformed rule bases: every problem is reported at its line and column, clearly worded."""

from __future__ import annotations

import re
import threading
from pathlib import Path
from string import Template

import numpy as np
import pytest

from fuzzkit import located_yaml
from fuzzkit.errors import Problem, RuleBaseError
from fuzzkit.formats import yaml_reader as dsl
from fuzzkit.formats.registry import loads
from fuzzkit.formats.yaml_reader import RULE_BASE_DOCUMENT
from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import Compound, Consequent, Proposition, Rule, RuleBase, Term, Variable
from fuzzkit.fuzzy.validation import check, ensure_valid

PART = "{partition: triangular, labels: [N, Z, P]}"
RULES = """\
rules:
  - {if: {e: N, de: N}, then: {du: N}}
  - {if: {e: P}, then: {du: P}}
"""
# Lines: 1 name, 3 input e, 4 input de, 6 output du, 7 'rules:', 8-9 rules, 10 the tail.
TEMPLATE = """\
name: $name
inputs:
  e: {range: [-1, 1]$e_extra, terms: $e}
  de: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  du: {range: [-1, 1]$du_default$du_extra, terms: $du}
$rules$tail"""


def doc(
    *,
    name: str = "demo",
    e: str = PART,
    du: str = PART,
    rules: str = RULES,
    tail: str = "",
    e_extra: str = "",
    du_extra: str = "",
) -> str:
    """The base document with one part replaced."""
    # RULES fire on a few label combinations only: the default makes the others warnings
    du_default = "" if du_extra.startswith(", default") else ", default: 0"
    return Template(TEMPLATE).substitute(
        name=name,
        e=e,
        du=du,
        rules=rules,
        tail=tail,
        e_extra=e_extra,
        du_extra=du_extra,
        du_default=du_default,
    )


GOOD = doc()
TABLE = "rules:\n  table:\n    rows: e\n    columns: de\n"


def problems(text: str) -> list[Problem]:
    with pytest.raises(RuleBaseError) as info:
        loads(text, source="bad.yaml")
    return list(info.value.problems)


def test_the_base_document_is_valid() -> None:
    # Every case below breaks exactly one thing in this document.
    rb = loads(GOOD)
    assert rb.input_names == ("e", "de")
    assert len(rb.rules) == 2


def rule(text: str) -> str:
    return "rules:\n  - " + text + "\n"


def e_terms(text: str) -> str:
    """Terms of input 'e': ``text`` (defining N) plus valid Z and P."""
    z_and_p = "Z: {shape: triangle, points: [-1, 0, 1]}, P: {shape: triangle, points: [0, 1, 2]}"
    return "{" + text + ", " + z_and_p + "}"


# (yaml_text, line, at, match): the problem matching ``match`` is reported on ``line`` at the
# column where the text ``at`` starts on that line.
CASES = [
    # --- YAML-level problems
    ("name: demo\n\tinputs: {}\n", 2, "\t", r"invalid YAML: .*tab"),
    ("name: [demo\n", 2, "", r"invalid YAML: .*expected ',' or ']'"),
    ("- just\n- a list\n", 1, "- just", r"expected a rule base \(a mapping\), got a list"),
    ("just a sentence\n", 1, "just", r"expected a rule base \(a mapping\), got 'just a sentence'"),
    ("name: a\n---\nname: b\n", 2, "---", r"invalid YAML: .*expected a single document"),
    # --- keys
    (
        doc(tail="defuzzifer: centroid\n"),
        10,
        "defuzzifer",
        r"unknown key 'defuzzifer' in the rule base \(did you mean 'defuzzifier'\?\)",
    ),
    (doc(tail="name: other\n"), 10, "name", r"duplicate key 'name' \(first defined on line 1\)"),
    (
        GOOD.replace("name: demo\n", ""),
        1,
        "inputs",
        r"missing required key 'name' in the rule base",
    ),
    (
        GOOD.replace("  e: {range", "  e: {rnage"),
        3,
        "rnage",
        r"unknown key 'rnage' in input 'e' \(did you mean 'range'\?\)",
    ),
    (doc(e_extra=", default: 0"), 3, "default", r"'default' is only allowed on outputs"),
    (
        doc(rules=rule("{if: {e: N}, then: {du: N}, wieght: 1}")),
        8,
        "wieght",
        r"unknown key 'wieght' in a rule \(did you mean 'weight'\?\)",
    ),
    (
        doc(rules=rule("{if: {e: N}, then: {du: N}, if: {e: P}}")),
        8,
        "if: {e: P}",
        r"duplicate key 'if' \(first defined on line 8\)",
    ),
    # --- wrong types
    (
        GOOD.replace("  e: {range: [-1, 1]", "  e: {range: [-1, abc]"),
        3,
        "abc",
        r"expected a number for the high end of the range of input 'e', got 'abc'",
    ),
    (
        GOOD.replace("  e: {range: [-1, 1]", "  e: {range: [-1, 0, 1]"),
        3,
        "[-1, 0",
        r"expected the range of input 'e' as \[low, high\], got 3 items",
    ),
    (
        GOOD.replace("outputs:\n  du:", "outputs:\n  du: 5\n  dx:"),
        6,
        "5",
        r"expected output 'du' as a mapping \{range: \[low, high\], terms: \.\.\.\}, got 5$",
    ),
    (
        doc(e="{partition: triangular, labels: [N, Z, yes, P]}"),
        3,
        "yes",
        r"expected a label name, got yes \(YAML reads an unquoted",
    ),
    (
        doc(rules=rule("{if: {e: N}, then: {du: N}, weight: high}")),
        8,
        "high",
        r"expected a number for the rule weight, got 'high'",
    ),
    (doc(rules="rules: 7\n"), 7, "7", r"expected rules as a list of \{if: \.\.\., then: \.\.\.\}"),
    # --- term shapes and parameters
    (
        doc(e=e_terms("N: {shape: triangle, points: [0.2, 0.1, 0.3]}")),
        3,
        "[0.2",
        r"triangle points must be ordered a <= b <= c, got \[0\.2, 0\.1, 0\.3\]",
    ),
    (
        doc(e=e_terms("N: {shape: triangel, points: [0, 1, 2]}")),
        3,
        "triangel",
        r"unknown shape 'triangel' \(did you mean 'triangle'\?\)",
    ),
    (
        doc(e=e_terms("N: {shape: gaussian, mean: 0, sigma: -0.2}")),
        3,
        "-0.2",
        r"gaussian sigma must be > 0, got -0\.2",
    ),
    (
        doc(e=e_terms("N: {shape: gaussian, mean: 0, sigma: 0.2, points: [1]}")),
        3,
        "points",
        r"unknown key 'points' in gaussian term 'N'; expected one of shape, mean, sigma",
    ),
    (
        doc(e=e_terms("N: {shape: trapezoid, points: [0, 1, 2]}")),
        3,
        "[0, 1, 2]",
        r"trapezoid needs 4 points, got 3",
    ),
    (
        doc(e=e_terms("N: {shape: bell, width: 0.5, slope: 0, centre: 0}")),
        3,
        "0, centre",
        r"bell slope must be > 0, got 0",
    ),
    (
        doc(e=e_terms("N: {shape: sigmoid, slope: 0, centre: 0}")),
        3,
        "0, centre",
        r"sigmoid slope must be non-zero",
    ),
    (
        doc(e=e_terms("N: {shape: left_shoulder, points: [-0.5, .nan]}")),
        3,
        "[-0.5",
        r"left_shoulder points must be finite numbers",
    ),
    (
        doc(e=e_terms("N: {points: [-1, 0]}")),
        3,
        "{points",
        r"missing required key 'shape' in term 'N'",
    ),
    (
        doc(e="{partition: triangular, labels: [Z]}"),
        3,
        "[Z]",
        r"a partition needs at least 2 labels, got 1",
    ),
    (
        doc(e="{partition: trianglar, labels: [N, Z, P]}"),
        3,
        "trianglar",
        r"unknown partition 'trianglar' \(did you mean 'triangular'\?\)",
    ),
    # --- ranges, coverage, defaults, names
    (
        GOOD.replace("  e: {range: [-1, 1]", "  e: {range: [1, -1]"),
        3,
        "[1, -1]",
        r"range must be \[low, high\] with finite low < high, got \[1\.0, -1\.0\]",
    ),
    (
        doc(
            e="{N: {shape: left_shoulder, points: [-0.5, -0.2]}, "
            "P: {shape: right_shoulder, points: [0.2, 0.5]}}"
        ),
        3,
        "{N:",
        r"input 'e' is not covered on \[-0\.2, 0\.2\]",
    ),
    (
        doc(
            e="{N: {shape: triangle, points: [-2, -1, 0]}, P: {shape: triangle, points: [0, 1, 2]}}"
        ),
        3,
        "{N:",
        # the engine's triangles compute 0 within 2^-54 of the vertex, not only at it
        r"input 'e' is not covered on \[-5\.55111\d*e-17, 5\.55111\d*e-17\]",
    ),
    (
        doc(du_extra=", default: 2"),
        6,
        "2,",
        r"default must be a finite number inside the range "
        r"\[-1\.0, 1\.0\], got 2\.0",
    ),
    (
        doc(name="3d-controller"),
        1,
        "3d",
        r"expected an identifier matching \[A-Za-z_\]\[A-Za-z0-9_\]\*, got '3d-controller'",
    ),
    # keywords (static, lambda) are valid names: tests/test_keyword_names.py (issue 29 item 6)
    (
        GOOD.replace("  du: {range", "  e: {range").replace("du:", "e:"),
        6,
        "e:",
        r"duplicate variable name 'e' \(already used by an input\)",
    ),
    (
        doc(e="{partition: triangular, labels: [N, Z, P, N]}"),
        3,
        "N]",
        r"duplicate term 'N' in input 'e'",
    ),
    # --- operators and policies
    (
        doc(tail="operators: {and: mini}\n"),
        10,
        "mini",
        r"unknown and operator 'mini' \(did you mean 'min'\?\); expected one of min, product",
    ),
    (
        doc(tail="defuzzifier: centriod\n"),
        10,
        "centriod",
        r"unknown defuzzifier 'centriod' \(did you mean 'centroid'\?\)",
    ),
    (
        doc(tail="out_of_range: wrap\n"),
        10,
        "wrap",
        r"unknown out_of_range policy 'wrap'; expected one of clamp, extend",
    ),
    (
        doc(du="{N: {shape: singleton, value: -1}, P: {shape: triangle, points: [0, 1, 2]}}"),
        6,
        "singleton, value: -1",
        r"singleton output term 'N' has no area",
    ),
    # --- rules
    (
        doc(rules=rule("{if: {e: PX}, then: {du: N}}")),
        8,
        "PX",
        r"unknown label 'PX' for input 'e' \(did you mean 'P'\?\); expected one of N, Z, P",
    ),
    (
        doc(rules=rule("{if: {e: N, dx: N}, then: {du: N}}")),
        8,
        "dx",
        r"unknown input 'dx' \(did you mean 'de'\?\)",
    ),
    (
        doc(rules=rule("{if: {du: N}, then: {du: N}}")),
        8,
        "du: N}, then",
        r"'du' is an output; conditions \(if\) may only use inputs",
    ),
    (
        doc(rules=rule("{if: {e: N}, then: {e: N}}")),
        8,
        "e: N}}",
        r"'e' is an input; conclusions \(then\) may only set outputs",
    ),
    (
        doc(rules=rule("{if: {e: N}, then: {du: N}, weight: 1.5}")),
        8,
        "1.5",
        r"weight must be in \[0, 1\], got 1\.5",
    ),
    (
        doc(rules=rule("{if: {or: [{e: N}]}, then: {du: N}}")),
        8,
        "or:",
        r"'or' needs at least 2 operands, got 1",
    ),
    (
        doc(rules=rule("{if: {not: {e: N, de: Z}}, then: {du: N}}")),
        8,
        "{e: N, de",
        r"'not' applies to one condition",
    ),
    (doc(rules=rule("{if: {e: N}}")), 8, "{if", r"missing required key 'then' in a rule"),
    (doc(rules="rules: []\n"), 7, "[]", r"the rule base has no rules"),
    # --- tables
    (
        doc(rules=TABLE + "    cells: |\n      N N N\n      N Z\n      Z P P\n"),
        13,
        "N Z",
        r"table row 2 has 2 cells, expected 3 \(one per label of columns input 'de'\)",
    ),
    (
        doc(rules=TABLE + "    cells: |\n      N N N\n      N Z P\n"),
        11,
        "|",
        r"table has 2 rows, expected 3 \(one per label of rows input 'e'\)",
    ),
    (
        doc(rules=TABLE + "    cells: |\n      N N N\n      N Z PX\n      Z P P\n"),
        13,
        "PX",
        r"unknown label 'PX' for output 'du' \(did you mean 'P'\?\)",
    ),
    (
        doc(
            rules=TABLE.replace("columns: de", "columns: dx") + "    cells: |\n      N N N\n"
            "      N Z P\n      Z P P\n"
        ),
        10,
        "dx",
        r"unknown input 'dx' \(did you mean 'de'\?\)",
    ),
    (
        doc(rules=TABLE + "    column_labels: [N, Z, Q]\n    cells: [N N N, N Z P, Z P P]\n"),
        11,
        "Q]",
        r"unknown label 'Q' for input 'de'",
    ),
    (
        doc(rules=TABLE + "    cells: [N N N, N Z P, Z P X]\n"),
        11,
        "X]",
        r"unknown label 'X' for output 'du'",
    ),
    (
        doc(rules=TABLE + "    cels: x\n"),
        11,
        "cels",
        r"unknown key 'cels' in the rule table \(did you mean 'cells'\?\)",
    ),
    # --- YAML features that are refused
    (doc(du_extra=", <<: {default: 0}"), 6, "<<", r"merge keys \(<<\) are not supported"),
    (doc(tail="? [a, b]\n: 1\n"), 10, "[a, b]", r"expected a name as key, got a list"),
]


@pytest.mark.parametrize(("yaml_text", "line", "at", "match"), CASES)
def test_malformed_rule_base_is_reported_at_its_line(
    yaml_text: str, line: int, at: str, match: str
) -> None:
    found = problems(yaml_text)
    hits = [p for p in found if re.search(match, p.message)]
    assert hits, f"no problem matches {match!r}; got:\n" + "\n".join(map(str, found))
    assert len(found) == 1, "one mistake, one message:\n" + "\n".join(map(str, found))
    where = hits[0].location
    assert where.file == "bad.yaml"
    assert where.line == line, str(hits[0])
    text_line = [*yaml_text.split("\n"), ""][line - 1]
    expected_col = text_line.index(at) + 1 if at else 1
    assert where.col == expected_col, f"{hits[0]} (expected column {expected_col}: {at!r})"


def test_there_are_at_least_25_malformed_cases() -> None:
    assert len(CASES) >= 25


def test_every_problem_is_collected_and_sorted_by_line() -> None:
    text = """\
name: 3d
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
  de: {range: [1, -1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  du: {range: [-1, 1], terms: {N: {shape: triangle, points: [0, -1, 1]}, P: {shape: bell,
       width: 1, slope: 2, centre: zz}}}
operators: {and: mini}
rules:
  - {if: {e: PX}, then: {du: N}, weight: 2}
  - {if: {e: N}, then: {du: P}, extra: 1}
"""
    found = problems(text)
    expected = [
        (1, r"expected an identifier"),
        (4, r"range must be \[low, high\]"),
        (6, r"triangle points must be ordered"),
        (7, r"expected a number for centre of term 'P', got 'zz'"),
        (8, r"unknown and operator 'mini'"),
        (10, r"unknown label 'PX' for input 'e'"),
        (10, r"weight must be in \[0, 1\]"),
        (11, r"unknown key 'extra' in a rule"),
    ]
    assert len(found) == len(expected), "\n".join(map(str, found))
    for problem, (line, pattern) in zip(found, expected, strict=True):
        assert problem.location.line == line, str(problem)
        assert re.search(pattern, problem.message), str(problem)
    with pytest.raises(RuleBaseError, match=r"^8 problems found:\nbad\.yaml:1:7: "):
        loads(text, source="bad.yaml")


def test_structural_errors_do_not_cascade_into_semantic_ones() -> None:
    # 'sigma: abc' is one problem; coverage of 'e' and the rules using 'N' must stay quiet.
    text = doc(
        e="{N: {shape: gaussian, mean: 0, sigma: abc}}", rules=rule("{if: {e: N}, then: {du: N}}")
    )
    found = problems(text)
    assert [p.message for p in found] == ["expected a number for sigma of term 'N', got 'abc'"]


def test_empty_file_is_a_message() -> None:
    for text in ("", "   \n# only a comment\n"):
        (p,) = problems(text)
        assert "file is empty" in p.message


def test_alias_bomb_is_refused_without_expanding_it() -> None:
    # Thirty levels of nine-fold aliases would expand to 9**30 nodes: a reader that expanded
    # them would never finish, so finishing at all shows the graph was measured, not expanded.
    lines = ['a0: &a0 ["x", "x", "x", "x", "x", "x", "x", "x", "x"]']
    for i in range(1, 30):
        refs = ", ".join([f"*a{i - 1}"] * 9)
        lines.append(f"a{i}: &a{i} [{refs}]")
    text = "\n".join(lines) + "\n" + GOOD.replace("rules:", "description: *a29\nrules:")
    found: list[Problem] = []
    worker = threading.Thread(target=lambda: found.extend(problems(text)), daemon=True)
    worker.start()
    worker.join(timeout=120.0)  # a hang guard, not a speed measurement
    assert not worker.is_alive(), "the alias bomb is being expanded"
    (p,) = found
    assert "expands to more than 100000 nodes through aliases" in p.message


def test_recursive_alias_is_refused() -> None:
    (p,) = problems("name: &x [*x]\n")
    assert "refers to itself" in p.message or "invalid YAML" in p.message


def test_huge_file_is_refused_before_parsing(monkeypatch: pytest.MonkeyPatch) -> None:
    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a file over the size limit reached the YAML parser")

    monkeypatch.setattr(located_yaml.yaml, "compose", never)
    text = GOOD + "# " + "x" * (located_yaml.MAX_FILE_BYTES + 10) + "\n"
    (p,) = problems(text)
    assert "limited to 1048576 bytes" in p.message


def test_huge_file_on_disk_is_refused_without_reading(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    path.write_text(GOOD + "#" * (located_yaml.MAX_FILE_BYTES + 1))
    with pytest.raises(RuleBaseError, match=r"big\.yaml: file is \d+ bytes; rule bases are "):
        dsl.load_file(path)


def test_deep_nesting_is_a_message_not_a_crash() -> None:
    (p,) = problems("name: " + "[" * 5000 + "]" * 5000 + "\n")
    # the top mapping is level 1: the 200th list (column 7 + 199) is the first one too deep
    assert (p.location.line, p.location.col) == (1, 206)
    assert p.message == (
        "mappings and lists nested too deeply (more than 200 levels); rule bases are limited "
        "to 200 levels"
    )


def test_nesting_up_to_the_limit_is_plain_yaml() -> None:
    # 200 levels of block mappings compose; the reader then judges the content, not the depth
    text = "".join(f"{'  ' * k}k{k}:\n" for k in range(199)) + "  " * 199 + "k: 1\n"
    assert located_yaml.compose_document(text, "deep.yaml", RULE_BASE_DOCUMENT) is not None
    (p,) = problems(text.replace("k: 1", "k: {a: 1}"))  # one more level
    assert (p.location.line, p.location.col) == (200, 2 * 199 + 4)
    assert "more than 200 levels" in p.message


def test_non_utf8_file_is_a_message(tmp_path: Path) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes(GOOD.replace("demo", "d\xe9mo").encode("latin-1"))
    with pytest.raises(RuleBaseError, match=r"not UTF-8 text"):
        dsl.load_file(path)


# ------------------------------------------------------------------- Python-built models


def _model(**overrides: object) -> RuleBase:
    e = Variable(
        "e",
        -1.0,
        1.0,
        (Term("N", "left_shoulder", (-0.5, 0.5)), Term("P", "right_shoulder", (-0.5, 0.5))),
    )
    du = Variable(
        "du",
        -1.0,
        1.0,
        (Term("N", "triangle", (-2.0, -1.0, 0.0)), Term("P", "triangle", (0.0, 1.0, 2.0))),
    )
    fields: dict[str, object] = {
        "name": "m",
        "inputs": (e,),
        "outputs": (du,),
        "rules": (
            Rule(Proposition("e", "N"), (Consequent("du", "N"),)),
            Rule(Proposition("e", "P"), (Consequent("du", "P"),)),
        ),
    }
    fields.update(overrides)
    return RuleBase(**fields)  # type: ignore[arg-type]


def test_python_built_model_is_checked_with_logical_paths() -> None:
    assert check(_model()) == []
    bad = _model(
        rules=(Rule(Compound("and", (Proposition("e", "NX"),)), (Consequent("du", "P"),), 1.5),)
    )
    issues = dict(check(bad))
    assert issues[("rules", 0, "if")] == "'and' needs at least 2 operands, got 1"
    assert issues[("rules", 0, "if", 0, "label")].startswith("unknown label 'NX' for input 'e'")
    assert issues[("rules", 0, "weight")] == "weight must be in [0, 1], got 1.5"
    with pytest.raises(RuleBaseError) as info:
        ensure_valid(bad)
    first = info.value.problems[0]
    assert str(first.location) == "<rulebase>"
    assert first.message.startswith("rules[0].if: ")


def test_coverage_is_exact_at_the_vertices() -> None:
    # Two triangles meeting at 0 with membership 0 there: x = 0 fires no rule, nor do the
    # floats within 2^-54 of it, where both compute to exactly 0 (1 - t rounds to 0)
    gap = Variable(
        "e",
        -1.0,
        1.0,
        (Term("N", "triangle", (-2.0, -1.0, 0.0)), Term("P", "triangle", (0.0, 1.0, 2.0))),
    )
    issues = dict(check(_model(inputs=(gap,))))
    edge = 2.0**-54
    assert f"not covered on [{-edge!r}, {edge!r}]" in issues[("inputs", "e", "terms")]
    mu = np.array([evaluate_term(t, np.array([-edge, 0.0, edge])) for t in gap.terms])
    assert np.all(mu == 0.0)  # the engine's own arithmetic, as the gap says
    beside = np.array([np.nextafter(-edge, -1.0), np.nextafter(edge, 1.0)])
    assert np.all(np.max([evaluate_term(t, beside) for t in gap.terms], axis=0) > 0.0)
    # A vertical edge (a == b) has membership 1 at a, so 0 itself is covered; left of it the
    # triangle computes 0 from -2^-54 and the edge (a slope of 1e200) rises only from -1e-200
    edge = Variable(
        "e",
        -1.0,
        1.0,
        (Term("N", "triangle", (-2.0, -1.0, 0.0)), Term("P", "trapezoid", (0.0, 0.0, 1.0, 1.0))),
    )
    (message,) = dict(check(_model(inputs=(edge,)))).values()
    assert f"not covered on [{-(2.0**-54)!r}, -1e-200]" in message
    at = np.array([-(2.0**-54), -1e-17, -1e-200, -1e-201, 0.0])
    mu = np.max([evaluate_term(t, at) for t in edge.terms], axis=0)
    assert list(mu[:3]) == [0.0, 0.0, 0.0] and mu[3] > 0.0 and mu[4] == 1.0


def test_python_object_tags_are_refused_not_read_as_data() -> None:
    text = "name: x\ndescription: !!python/object/apply:os.system [ls]\ninputs: {}\n"
    with pytest.raises(RuleBaseError) as info:
        loads(text, source="tag.yaml")
    (problem,) = info.value.problems
    assert str(problem.location) == "tag.yaml:2:14"
    assert "unsupported YAML tag" in problem.message and "python/object/apply" in problem.message


@pytest.mark.parametrize("word", ["OFF", "on", "Yes", "no", "true"])
def test_an_unquoted_boolean_word_as_a_term_name_says_why(word: str) -> None:
    found = problems(doc(e=e_terms(word + ": {shape: triangle, points: [-2, -1, 0]}")))
    messages = [p.message for p in found]
    assert any(
        m.startswith(f"expected a name as key, got {word}")
        and "reads an unquoted yes/no/on/off/true/false as a boolean; quote it" in m
        for m in messages
    ), messages


@pytest.mark.parametrize(
    "cells",
    [
        "      N N N\n      N Z\n      Z PX P\n",  # a short row before the typo
        "      N N NX\n      N Z\n      Z P P\n",  # ... and after it
        "      N N N\n      N Z P\n      Z PX P\n      P P P\n",  # a row too many
        "      N N N\n      Z PX P\n",  # a row too few
    ],
)
def test_a_label_typo_is_reported_even_beside_a_table_of_the_wrong_shape(cells: str) -> None:
    # issue 29 item 7: the shape error used to hide every label typo of the same table
    text = doc(rules=TABLE + "    cells: |\n" + cells)
    found = problems(text)
    typo = "PX" if "PX" in cells else "NX"
    line = 11 + next(i for i, row in enumerate(cells.splitlines(), 1) if typo in row)
    (hit,) = [p for p in found if f"unknown label {typo!r} for output 'du'" in p.message]
    assert (hit.location.line, hit.location.col) == (
        line,
        text.splitlines()[line - 1].index(typo) + 1,
    )
    assert any("table" in p.message and "expected" in p.message for p in found if p is not hit)
