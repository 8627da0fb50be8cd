"""Malformed and inexpressible FIS, FCL and FLL files: every problem located file:line:col."""

from __future__ import annotations

import pytest

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import fcl, fis, fll

FIS = """[System]
Name='tank'
Type='mamdani'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=2
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='level'
Range=[0 1]
NumMFs=2
MF1='low':'trapmf',[-inf -inf 0.2 0.8]
MF2='high':'trapmf',[0.2 0.8 inf inf]

[Input2]
Name='rate'
Range=[-1 1]
NumMFs=1
MF1='any':'gaussmf',[1 0]

[Output1]
Name='valve'
Range=[0 1]
NumMFs=2
MF1='shut':'trimf',[0 0 0.6]
MF2='open':'trimf',[0.4 1 1]

[Rules]
1 1, 2 (1) : 1
2 -1, 1 (0.5) : 2
"""

FLL = """Engine: tank
InputVariable: level
  enabled: true
  range: 0 1
  lock-range: false
  term: low Ramp 0.8 0.2
  term: high Ramp 0.2 0.8
OutputVariable: valve
  enabled: true
  range: 0 1
  lock-range: false
  aggregation: Maximum
  defuzzifier: Centroid 100
  default: nan
  lock-previous: false
  term: shut Triangle 0 0 0.6
  term: open Triangle 0.4 1 1
RuleBlock: r
  enabled: true
  conjunction: Minimum
  disjunction: Maximum
  implication: Minimum
  activation: General
  rule: if level is low then valve is open
  rule: if level is high then valve is shut
"""

FCL = """FUNCTION_BLOCK tank
VAR_INPUT
  level : REAL;
END_VAR
VAR_OUTPUT
  valve : REAL;
END_VAR
FUZZIFY level
  RANGE := (0 .. 1);
  TERM low := (0.2, 1) (0.8, 0);
  TERM high := (0.2, 0) (0.8, 1);
END_FUZZIFY
DEFUZZIFY valve
  RANGE := (0 .. 1);
  TERM shut := (0, 1) (0.6, 0);
  TERM open := (0.4, 0) (1, 1);
  METHOD : COG;
  DEFAULT := 0;
END_DEFUZZIFY
RULEBLOCK r
  AND : MIN;
  ACCU : MAX;
  RULE 1 : IF level IS low THEN valve IS open;
  RULE 2 : IF level IS high THEN valve IS shut;
END_RULEBLOCK
END_FUNCTION_BLOCK
"""

#: The level input's RANGE and terms (cases take them away: the range cannot be derived).
FCL_LEVEL_TERMS = (
    "  RANGE := (0 .. 1);\n  TERM low := (0.2, 1) (0.8, 0);\n  TERM high := (0.2, 0) (0.8, 1);"
)
READERS = {"fis": (fis.loads, FIS), "fll": (fll.loads, FLL), "fcl": (fcl.loads, FCL)}


def test_the_valid_bases_load() -> None:
    for loads, text in READERS.values():
        assert loads(text, "t").name == "tank"


@pytest.mark.parametrize(
    "fmt, old, new, match",
    [
        # ---- .fis: structure
        ("fis", "NumRules=2", "NumRules=3", r"t:34:1: NumRules=3 but \[Rules\] has 2 rule lines"),
        (
            "fis",
            "[Rules]\n1 1, 2 (1) : 1\n2 -1, 1 (0.5) : 2\n",
            "",
            r"t:\d+:1: missing \[Rules\] section \(truncated file\?\)",
        ),
        (
            "fis",
            "NumMFs=2\nMF1='low'",
            "NumMFs=3\nMF1='low'",
            r"t:14:1: \[Input1\]: NumMFs=3 but MF3 is missing",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "3 1, 2 (1) : 1",
            r"t:35:1: rule 1: input 'level' has 2 terms, the rule uses term 3",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "1 1, 5 (1) : 1",
            r"t:35:1: rule 1: output 'valve' has 2 terms, the rule uses term 5",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "1 1 1, 2 (1) : 1",
            r"t:35:1: rule 1: expected 2 input and 1 output indices, got 3 and 1",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "1 1, 2 (1) : 3",
            r"t:35:14: rule 1: connective must be 1 \(AND\) or 2 \(OR\), got '3'",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "1.2 1, 2 (1) : 1",
            r"t:35:1: rule 1: .*hedges are not supported",
        ),
        (
            "fis",
            "1 1, 2 (1) : 1",
            "1 1, -2 (1) : 1",
            r"t:35:1: rule 1: .*negated or hedged conclusions",
        ),
        (
            "fis",
            "Range=[0 1]\nNumMFs=2\nMF1='low'",
            "Range=[1 0]\nNumMFs=2\nMF1='low'",
            r"t:16:7: inputs.level.range: range must be \[low, high\] with finite low < high",
        ),
        (
            "fis",
            "MF1='low':'trapmf',[-inf -inf 0.2 0.8]",
            "MF1='low':'trapmf',[0.2 0.8]",
            r"t:18:5: \[Input1\] MF1 \('low'\): trapmf needs 4 parameters, got 2",
        ),
        (
            "fis",
            "MF1='shut':'trimf',[0 0 0.6]",
            "MF1='shut':'trimf',[0.6 0 0]",
            r"t:31:5: outputs.valve.terms.shut.points: triangle points must be ordered",
        ),
        (
            "fis",
            "MF2='open':'trimf'",
            "MF2='shut':'trimf'",
            r"t:32:5: \[Output1\] MF2: term name 'shut' is already MF1 of 'valve'; .*unambiguous",
        ),
        ("fis", "Name='rate'", "Name='level'", r"duplicate variable name 'level'"),
        # ---- .fis: constructs fuzzkit cannot express
        (
            "fis",
            "'trimf',[0 0 0.6]",
            "'cosinemf',[0 0.6]",
            r"t:31:5: \[Output1\] MF1 \('shut'\): membership function 'cosinemf' is not in",
        ),
        (
            "fis",
            "'trimf',[0 0 0.6]",
            "'myshape',[0 0.6]",
            r"t:31:5: .*custom membership function 'myshape'",
        ),
        (
            "fis",
            "AggMethod='max'",
            "AggMethod='sum'",
            r"t:11:11: \[System\] AggMethod: .*unbounded sum",
        ),
        (
            "fis",
            "ImpMethod='min'",
            "ImpMethod='myimp'",
            r"t:10:11: \[System\] ImpMethod: 'myimp' is not one of min, prod \(custom functions",
        ),
        (
            "fis",
            "DefuzzMethod='centroid'",
            "DefuzzMethod='wtaver'",
            r"t:12:14: \[System\] DefuzzMethod: 'wtaver' does not go with Type='mamdani'",
        ),
        (
            "fis",
            "Type='mamdani'",
            "Type='mamdanitype2'",
            r"t:3:6: \[System\] Type: expected 'mamdani' or 'sugeno'",
        ),
        ("fis", "[System]", "[Sistem]", r"t:1:1: missing \[System\] section"),
        # ---- .fll
        (
            "fll",
            "if level is low then",
            "if level is very low then",
            r"t:24:21: hedge 'very' cannot be expressed in fuzzkit",
        ),
        (
            "fll",
            "if level is low then",
            "if level is lowest then",
            r"t:24:21: unknown term 'lowest' of input 'level'; expected one of low, high",
        ),
        (
            "fll",
            "if level is low then",
            "if depth is low then",
            r"t:24:12: unknown input 'depth'; expected one of level",
        ),
        ("fll", "valve is open", "valve is not open", r"t:24:39: 'not' in a conclusion cannot"),
        (
            "fll",
            "if level is low then",
            "if level is low or level is high and level is low then",
            r"t:24:\d+: mixing 'and' and 'or' without parentheses is ambiguous",
        ),
        (
            "fll",
            "if level is low then valve is open",
            "if level is low then valve is",
            r"t:24:\d+: rule ends early \(expected a term name\)",
        ),
        (
            "fll",
            "term: high Ramp 0.2 0.8",
            "term: high Cosine 0.5 0.2",
            r"t:7:9: term 'high': Cosine is not in fuzzkit's model",
        ),
        (
            "fll",
            "term: high Ramp 0.2 0.8",
            "term: low Ramp 0.2 0.8",
            r"t:7:9: term name 'low' appears twice in input 'level'",
        ),
        (
            "fll",
            "term: shut Triangle 0 0 0.6",
            "term: shut Triangle 0 0.6",
            r"t:16:9: term 'shut': Triangle needs 3 parameters, got 2",
        ),
        (
            "fll",
            "activation: General",
            "activation: Highest 2",
            r"t:23:15: activation: 'Highest 2' cannot be expressed",
        ),
        ("fll", "lock-previous: false", "lock-previous: true", r"t:15:18: lock-previous: true"),
        (
            "fll",
            "range: 0 1\n  lock-range: false\n  term: low",
            "range: 1 0\n  lock-range: false\n  term: low",
            r"t:4:10: inputs.level.range: range must be",
        ),
        (
            "fll",
            "RuleBlock: r",
            "RuleBlok: r",
            r"t:18:1: expected 'Engine: name'|unknown key 'RuleBlok'",
        ),
        # ---- .fcl
        (
            "fcl",
            "END_FUNCTION_BLOCK\n",
            "",
            r"t:\d+:1: missing END_FUNCTION_BLOCK \(truncated file\?\)",
        ),
        (
            "fcl",
            "IS low THEN",
            "IS somewhat low THEN",
            r"t:23:24: hedge 'somewhat' cannot be expressed",
        ),
        (
            "fcl",
            "TERM high := (0.2, 0) (0.8, 1)",
            "TERM high := (0.2, 0) (0.5, 0.5) (0.8, 1)",
            r"t:11:16: TERM high: only point lists with memberships 0 and 1",
        ),
        (
            "fcl",
            "TERM high := (0.2, 0) (0.8, 1)",
            "TERM high := (0.8, 0) (0.2, 1)",
            r"t:11:16: TERM high: point x values must not decrease",
        ),
        ("fcl", "DEFAULT := 0;", "DEFAULT := 0 | NC;", r"t:18:14: DEFAULT \.\.\. \| NC"),
        (
            "fcl",
            "ACCU : MAX;",
            "ACCU : NSUM;",
            r"t:22:3: ACCU : NSUM cannot be expressed|t:22:\d+: ACCU : NSUM",
        ),
        ("fcl", "METHOD : COG;", "METHOD : COGF;", r"t:17:\d+: METHOD : COGF cannot be expressed"),
        (
            "fcl",
            FCL_LEVEL_TERMS,
            "",
            r"t:8:1: input 'level' has no RANGE := \(low \.\. high\) and no terms to derive",
        ),
        (
            "fcl",
            FCL_LEVEL_TERMS,
            "  TERM low := 0.5;\n  TERM high := 0.5;",
            r"t:8:1: input 'level' has no RANGE := \(low \.\. high\), and its terms all sit at",
        ),
        (
            "fcl",
            "THEN valve IS open",
            "THEN pump IS open",
            r"t:23:33: unknown output 'pump'; expected one of valve",
        ),
        ("fcl", "FUZZIFY level", "FUZZIFY lvl", r"t:8:9: FUZZIFY lvl: no input 'lvl' declared"),
        (
            "fcl",
            "TERM open := (0.4, 0) (1, 1)",
            "TERM shut := (0.4, 0) (1, 1)",
            r"t:16:3: term name 'shut' appears twice in output 'valve'",
        ),
    ],
)
def test_bad_files_are_refused_with_their_location(
    fmt: str, old: str, new: str, match: str
) -> None:
    loads, text = READERS[fmt]
    assert old in text, "the test's anchor text must be in the base file"
    with pytest.raises(RuleBaseError, match=match) as err:
        loads(text.replace(old, new, 1), "t")
    assert "Traceback" not in str(err.value)


@pytest.mark.parametrize(
    "fmt, cut, match",
    [
        (
            "fis",
            "[Output1]",
            r"t:6:12: NumOutputs=1 but \[Output1\] is missing \(truncated file\?\)",
        ),
        ("fll", "RuleBlock:", r"t:\d+:1: expected one RuleBlock, got 0 \(truncated file\?\)"),
        ("fcl", "RULEBLOCK", r"t:\d+:1: missing END_FUNCTION_BLOCK \(truncated file\?\)"),
    ],
)
def test_truncated_files_are_refused(fmt: str, cut: str, match: str) -> None:
    loads, text = READERS[fmt]
    with pytest.raises(RuleBaseError, match=match):
        loads(text[: text.index(cut)], "t")


def test_every_problem_is_listed_not_only_the_first() -> None:
    text = FIS.replace("'trimf',[0 0 0.6]", "'cosinemf',[0 0.6]").replace(
        "1 1, 2 (1) : 1", "1 1, 9 (1) : 1"
    )
    with pytest.raises(RuleBaseError) as err:
        fis.loads(text, "t")
    assert len(err.value.problems) >= 2


def test_hostile_nesting_and_unterminated_comments_fail_cleanly_and_fast() -> None:
    deep = FLL.replace(
        "if level is low then", "if " + "(" * 5000 + "level is low" + ")" * 5000 + " then"
    )
    with pytest.raises(RuleBaseError, match=r"t:24:\d+: parentheses nested deeper than 32"):
        fll.loads(deep, "t")
    with pytest.raises(RuleBaseError, match="missing END_FUNCTION_BLOCK"):
        fcl.loads(FCL.replace("END_RULEBLOCK", "(*" * 200_000, 1), "t")
