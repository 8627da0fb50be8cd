"""FCL as IEC 61131-7 and jFuzzyLogic write it: no RANGE, the range derived from the terms.

The files in tests/data/fcl/ are written in the standard's and jFuzzyLogic's style (no RANGE
in FUZZIFY or DEFUZZIFY, RANGE after a VAR declaration, point lists and named shapes, ``//``,
``(* *)`` and ``/* */`` comments, ACCU in either block, OR left to De Morgan). Their outputs are
checked against values worked out by hand from the FCL text (closed form), or, where the
aggregated set has no short closed form, against a fine quadrature of the membership functions
written out below from the file's definitions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import fuzzkit
from fuzzkit.cli import main
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import fcl
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.model import RuleBase, Term

DATA = Path(__file__).resolve().parent / "data" / "fcl"


def rulebase(name: str) -> RuleBase:
    return fcl.load(DATA / name)


# ------------------------------------------------------------------- derived ranges


@pytest.mark.parametrize(
    "name, ranges",
    [
        # point lists: first to last point of every term (held constant beyond them)
        ("tipping.fcl", {"service": (0, 10), "food": (0, 10), "tip": (0, 30)}),
        # named shapes: the span of their parameters
        ("valve.fcl", {"pressure": (-4, 4), "rate": (-1, 1), "valve": (-10, 10)}),
        # the input's points; the output's RANGE is given and kept
        ("heater.fcl", {"error": (-3, 3), "power": (0, 100)}),
        # RANGE after the VAR declaration (jFuzzyLogic) kept; the output derived
        ("level.fcl", {"error": (-20, 20), "inflow": (-2, 2)}),
        # smooth shapes, as jFuzzyLogic estimates their universe: gaussian mean +- 4 sigma,
        # sigmoid centre +- 9/|slope|, bell centre +- a * 999^(1/2b) (where it is 0.001)
        (
            "smooth.fcl",
            {
                "temp": (40 - 4 * 5, 70 + 4 * 10),
                "humidity": (60 - 10 * 999 ** (1 / 4), 60 + 10 * 999 ** (1 / 4)),
                "burner": (0, 100),
            },
        ),
    ],
)
def test_a_variable_without_range_spans_its_terms(
    name: str, ranges: dict[str, tuple[float, float]]
) -> None:
    rb = rulebase(name)
    got = {v.name: (v.low, v.high) for v in rb.inputs + rb.outputs}
    assert got.keys() == ranges.keys()
    for var, (low, high) in ranges.items():
        assert got[var] == pytest.approx((low, high), rel=1e-15, abs=1e-15), var


@pytest.mark.parametrize(
    "term, span",
    [
        (Term("t", "s_shape", (2.0, 5.0)), (2.0, 5.0)),
        (Term("t", "z_shape", (2.0, 5.0)), (2.0, 5.0)),
        (Term("t", "pi_shape", (1.0, 2.0, 3.0, 4.0)), (1.0, 4.0)),
        # each gaussian half 4 sigma beyond its mean
        (Term("t", "gaussian_product", (3.0, 0.5, 6.0, 2.0)), (1.0, 14.0)),
        (Term("t", "sigmoid", (-0.5, 30.0)), (12.0, 48.0)),
        (Term("t", "sigmoid_difference", (2.0, 3.0, 2.0, 6.0)), None),
        (Term("t", "linear", (1.0, 0.0)), None),
    ],
)
def test_the_span_of_each_shape(term: Term, span: tuple[float, float] | None) -> None:
    assert fcl.term_span("named", term) == span


def test_only_the_variables_without_range_get_a_note() -> None:
    _, _, notes = fcl.load_with_notes(DATA / "heater.fcl")
    assert notes == {"error": "derived: the span of its terms (no RANGE in heater.fcl)"}
    _, _, notes = fcl.load_with_notes(DATA / "level.fcl")
    assert set(notes) == {"inflow"}


# --------------------------------------------------------- outputs against hand values


def clipped_triangle_area(base: float, h: float) -> float:
    """A symmetric triangle of height 1 on ``base``, clipped at ``h``: a trapezoid."""
    return base * h * (2 - h) / 2


@pytest.mark.parametrize(
    "service, food, want",
    [
        (5, 5, 15.0),  # only 'good' (1): the medium triangle, centroid 15
        (9, 9, 25.0),  # excellent and tasty 0.75: high clipped symmetric, centroid 25
        (10, 5, 0.0),  # excellent 1 but tasty 0, nothing else: no rule fires, DEFAULT 0
        # poor 0.5 (OR rancid 0) clips low at 0.5; good 1/3 clips medium: two disjoint
        # symmetric trapezoids, centroids 5 and 15
        (
            2,
            8,
            (clipped_triangle_area(10, 0.5) * 5 + clipped_triangle_area(10, 1 / 3) * 15)
            / (clipped_triangle_area(10, 0.5) + clipped_triangle_area(10, 1 / 3)),
        ),
    ],
)
def test_tipping_at_hand_computed_points(service: float, food: float, want: float) -> None:
    got = fuzzkit.evaluate_point(rulebase("tipping.fcl"), {"service": service, "food": food})
    assert got["tip"] == pytest.approx(want, abs=1e-12)
    assert want != 0.0 or got["tip"] == 0.0


@pytest.mark.parametrize(
    "error, want",
    [
        (1.0, (100 * (1 / 3) + 50 * 0.5) / (1 / 3 + 0.5)),  # cold 1/3, fine 1/2: COGS = 70
        (3.0, 100.0),  # cold only
        (-0.5, (50 * 0.75 + 0 * (1 / 6)) / (0.75 + 1 / 6)),  # fine 3/4, warm 1/6
    ],
)
def test_heater_singletons_weighted_average(error: float, want: float) -> None:
    got = fuzzkit.evaluate_point(rulebase("heater.fcl"), {"error": error})["power"]
    assert got == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize(
    "error, want",
    [
        (-10.0, 1.0),  # below 1: 'more' (0 1 2) whole, its one maximum at 1
        (2.5, 0.5),  # on 1/2 clips 'same' to a plateau [-0.5, 0.5]; 'less' only 0.25
        (10.0, -0.5),  # above 1, weighted 0.5: 'less' clipped at 0.5, plateau [-1.5, -0.5]
    ],
)
def test_level_largest_of_maximum(error: float, want: float) -> None:
    got = fuzzkit.evaluate_point(rulebase("level.fcl"), {"error": error})["inflow"]
    assert got == pytest.approx(want, abs=1e-12)


def tri(x: np.ndarray, a: float, b: float, c: float) -> np.ndarray:
    left = np.where(b > a, (x - a) / max(b - a, 1e-300), 1.0)
    right = np.where(c > b, (c - x) / max(c - b, 1e-300), 1.0)
    return np.clip(np.minimum(left, right), 0.0, 1.0)


def centroid(x: np.ndarray, mu: np.ndarray) -> float:
    return float(np.trapezoid(mu * x, x) / np.trapezoid(mu, x))


def bisector(x: np.ndarray, mu: np.ndarray) -> float:
    area = np.concatenate([[0.0], np.cumsum((mu[1:] + mu[:-1]) / 2 * np.diff(x))])
    return float(np.interp(area[-1] / 2, area, x))


FINE = np.linspace(-10.0, 10.0, 2_000_001)


def test_valve_product_and_de_morgan_or_against_quadrature() -> None:
    rb = rulebase("valve.fcl")
    assert (rb.operators.and_, rb.operators.or_) == ("product", "probabilistic_sum")
    # pressure 1: ok 0.5, high 0.5 (TRAPE 0 2 4 4); rate 0.5: steady 0.5, rising 0.5
    r2 = 0.5 * 0.5  # ok AND steady (PROD)
    r3 = 0.5 + 0.5 - 0.5 * 0.5  # high OR rising: ASUM, the De Morgan partner of PROD
    mu = np.maximum(r2 * tri(FINE, -5, 0, 5), r3 * tri(FINE, -10, -5, 0))  # ACT PROD, ACCU MAX
    got = fuzzkit.evaluate_point(rb, {"pressure": 1.0, "rate": 0.5})["valve"]
    assert got == pytest.approx(centroid(FINE, mu), abs=1e-8)
    # pressure -3: low 1 (its plateau) and nothing else: 'open' whole, centroid 5
    assert fuzzkit.evaluate_point(rb, {"pressure": -3.0, "rate": 0.0})["valve"] == (
        pytest.approx(5.0, abs=1e-12)
    )


def test_smooth_shapes_bisector_against_quadrature() -> None:
    rb = rulebase("smooth.fcl")
    temp, humidity = 45.0, 50.0
    cool = math.exp(-((temp - 40) ** 2) / (2 * 5**2))
    hot = math.exp(-((temp - 70) ** 2) / (2 * 10**2))
    dry = 1 / (1 + math.exp(0.5 * (humidity - 30)))  # sigm -0.5 30
    damp = 1 / (1 + abs((humidity - 60) / 10) ** (2 * 2))  # gbell a=10 b=2 mean=60
    x = np.linspace(0.0, 100.0, 2_000_001)
    mu = np.maximum(
        np.minimum(min(cool, damp), tri(x, 50, 100, 100)),
        np.minimum(max(hot, dry), tri(x, 0, 0, 50)),
    )
    got = fuzzkit.evaluate_point(rb, {"temp": temp, "humidity": humidity})["burner"]
    assert got == pytest.approx(bisector(x, mu), abs=1e-6)


# --------------------------------------------------------------- De Morgan, errors


FCL_TEMPLATE = """FUNCTION_BLOCK t
VAR_INPUT
  a : REAL;
  b : REAL;
END_VAR
VAR_OUTPUT
  y : REAL;
END_VAR
FUZZIFY a
  TERM lo := (0, 1) (1, 0);
  TERM hi := (0, 0) (1, 1);
END_FUZZIFY
FUZZIFY b
  TERM lo := (0, 1) (1, 0);
  TERM hi := (0, 0) (1, 1);
END_FUZZIFY
DEFUZZIFY y
  TERM n := (-1, 0) (0, 1) (1, 0);
  TERM p := (0, 0) (1, 1) (2, 0);
  METHOD : COG;
END_DEFUZZIFY
RULEBLOCK r
{ops}
  RULE 1 : IF a IS hi OR b IS hi THEN y IS p;
  RULE 2 : IF a IS lo AND b IS lo THEN y IS n;
END_RULEBLOCK
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize(
    "ops, and_, or_",
    [
        ("", "min", "max"),
        ("  AND : MIN;", "min", "max"),
        ("  AND : PROD;", "product", "probabilistic_sum"),
        ("  OR : ASUM;", "product", "probabilistic_sum"),
        ("  OR : MAX;", "min", "max"),
        ("  AND : PROD;\n  OR : MAX;", "product", "max"),  # both declared: kept as written
    ],
)
def test_or_is_the_de_morgan_partner_of_and(ops: str, and_: str, or_: str) -> None:
    rb = fcl.loads(FCL_TEMPLATE.format(ops=ops))
    assert (rb.operators.and_, rb.operators.or_) == (and_, or_)


@pytest.mark.parametrize(
    "old, new, match",
    [
        (  # no terms and no RANGE: nothing to derive the range from
            "  TERM lo := (0, 1) (1, 0);\n  TERM hi := (0, 0) (1, 1);\nEND_FUZZIFY\nFUZZIFY b",
            "END_FUZZIFY\nFUZZIFY b",
            r"t:9:1: input 'a' has no RANGE := \(low \.\. high\) and no terms to derive it",
        ),
        (  # one point only: a range of no width
            "  TERM n := (-1, 0) (0, 1) (1, 0);\n  TERM p := (0, 0) (1, 1) (2, 0);",
            "  TERM n := (0, 1);\n  TERM p := (0, 1);",
            r"t:17:1: output 'y' has no RANGE := \(low \.\. high\), and its terms all sit at 0",
        ),
        (  # a term that does not parse: reported where it is, no guessed range
            "  TERM hi := (0, 0) (1, 1);\nEND_FUZZIFY\nFUZZIFY b",
            "  TERM hi := Triangle 0 x 1;\nEND_FUZZIFY\nFUZZIFY b",
            r"t:11:14: TERM hi: Triangle: expected numbers",
        ),
        (  # NC (keep the previous output) alone, as IEC allows it: not in fuzzkit's model
            "  METHOD : COG;\n",
            "  METHOD : COG;\n  DEFAULT := NC;\n",
            r"t:21:14: DEFAULT \.\.\. \| NC \(keep the previous value",
        ),
        (  # RANGE in a VAR section before any declaration
            "VAR_INPUT\n  a : REAL;",
            "VAR_INPUT\n  RANGE := (0 .. 1);\n  a : REAL;",
            r"t:3:3: RANGE before any variable declaration",
        ),
    ],
)
def test_ranges_that_cannot_be_derived_are_located(old: str, new: str, match: str) -> None:
    text = FCL_TEMPLATE.format(ops="")
    assert old in text
    with pytest.raises(RuleBaseError, match=match):
        fcl.loads(text.replace(old, new, 1), "t")


def test_a_sugeno_linear_output_needs_its_range() -> None:
    text = (
        FCL_TEMPLATE.format(ops="")
        .replace("TERM n := (-1, 0) (0, 1) (1, 0);", "TERM n := Linear 1 1 0;")
        .replace("TERM p := (0, 0) (1, 1) (2, 0);", "TERM p := 2;")
        .replace("METHOD : COG;", "METHOD : COGS;")
    )
    with pytest.raises(RuleBaseError, match=r"t:18:3: output 'y' has no RANGE .*TERM n \(linear\)"):
        fcl.loads(text, "t")
    ranged = text.replace("DEFUZZIFY y\n", "DEFUZZIFY y\n  RANGE := (-1 .. 3);\n")
    assert fcl.loads(ranged, "t").outputs[0].low == -1.0


# ------------------------------------------------------------------------------ CLI


def test_import_documents_each_derived_range_in_the_yaml(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "heater.yaml"
    assert main(["import", str(DATA / "heater.fcl"), "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    ranges = [line.strip() for line in lines if line.strip().startswith("range:")]
    assert ranges == [
        "range: [-3.0, 3.0]  # derived: the span of its terms (no RANGE in heater.fcl)",
        "range: [0.0, 100.0]",  # given in the file: no comment
    ]
    assert load(out) == fcl.load(DATA / "heater.fcl")


@pytest.mark.parametrize("name", sorted(p.name for p in DATA.glob("*.fcl")))
def test_imported_yaml_evaluates_like_the_fcl(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rb.yaml"
    assert main(["import", str(DATA / name), "--out", str(out)]) == 0
    yaml_rb, fcl_rb = load(out), fcl.load(DATA / name)
    assert yaml_rb == fcl_rb
    rng = np.random.default_rng(7)
    points = {v.name: rng.uniform(v.low, v.high, 50) for v in fcl_rb.inputs}
    a, b = fuzzkit.evaluate(yaml_rb, points), fuzzkit.evaluate(fcl_rb, points)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])


def test_import_of_an_underivable_range_fails_located_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.fcl"
    bad.write_text(
        FCL_TEMPLATE.format(ops="").replace(
            "  TERM lo := (0, 1) (1, 0);\n  TERM hi := (0, 0) (1, 1);\nEND_FUZZIFY\nFUZZIFY b",
            "END_FUZZIFY\nFUZZIFY b",
            1,
        )
    )
    out = tmp_path / "rb.yaml"
    code = main(["import", str(bad), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{bad}:9:1: input 'a' has no RANGE := (low .. high) and no terms" in err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == [bad]
