"""The shipped rule bases say what they claim: tables checked against independent references."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzkit import evaluate, evaluate_point
from fuzzkit.formats.registry import available, load
from fuzzkit.fuzzy.model import Compound, Proposition, RuleBase
from fuzzkit.fuzzy.validation import check

LABELS = ["NL", "NM", "NS", "ZR", "PS", "PM", "PL"]  # index -3 .. 3

# Table I of the paper, typed in from the printed page: rows e = PL (top) .. NL (bottom),
# columns de = NL .. PL. The paper prints the cells in lower case.
PAPER_TABLE_I = """\
e\\de NL NM NS ZR PS PM PL
PL    nl nm ns zr pm pl pl
PM    nl nl nm zr pm pl pl
PS    nl nl ns zr ps pl pl
ZR    nl nm ns zr ps pm pl
NS    nl nl ns zr ps pl pl
NM    nl nl nm zr pm pl pl
NL    nl nl nm zr ps pm pl
"""


def table_of(rb: RuleBase) -> dict[tuple[str, str], str]:
    """{(e label, de label): du label} from the model's rules (each must be a plain cell)."""
    cells: dict[tuple[str, str], str] = {}
    for rule in rb.rules:
        a = rule.antecedent
        assert isinstance(a, Compound) and a.op == "and"
        r, c = a.operands
        assert isinstance(r, Proposition) and isinstance(c, Proposition)
        assert (r.variable, c.variable) == ("e", "de")
        assert rule.weight == 1.0 and len(rule.consequents) == 1
        assert (r.term, c.term) not in cells
        cells[r.term, c.term] = rule.consequents[0].term
    return cells


def test_every_shipped_rule_base_is_valid_and_described() -> None:
    assert len(available()) >= 4
    for name in available():
        rb = load(name)
        assert check(rb) == []
        assert rb.name == name
        assert len(rb.description) > 40, f"{name} needs a description saying what it is"


def test_macvicar_whelan_is_the_saturated_sum() -> None:
    cells = table_of(load("macvicar_whelan"))
    assert len(cells) == 49
    for i_e in range(-3, 4):
        for i_de in range(-3, 4):
            expected = LABELS[max(-3, min(3, i_e + i_de)) + 3]
            assert cells[LABELS[i_e + 3], LABELS[i_de + 3]] == expected


def test_macvicar_whelan_variables_and_operators() -> None:
    rb = load("macvicar_whelan")
    assert rb.input_names == ("e", "de") and rb.output_names == ("du",)
    for var in (*rb.inputs, *rb.outputs):
        assert (var.low, var.high) == (-1.0, 1.0)
        assert var.term_names == tuple(LABELS)
    for var in rb.inputs:
        assert var.terms[0].shape == "left_shoulder" and var.terms[-1].shape == "right_shoulder"
        assert [t.shape for t in var.terms[1:-1]] == ["triangle"] * 5
    du = rb.outputs[0]
    assert all(t.shape == "triangle" for t in du.terms)
    assert [t.params[1] for t in du.terms] == pytest.approx([k / 3 for k in range(-3, 4)])
    assert du.terms[0].params == pytest.approx((-4 / 3, -1.0, -2 / 3))
    ops = rb.operators
    assert (ops.and_, ops.implication, ops.aggregation) == ("min", "min", "max")
    assert rb.defuzzifier == "centroid"


def test_paper_table1_matches_the_printed_table_cell_by_cell() -> None:
    rb = load("paper_table1")
    lines = PAPER_TABLE_I.splitlines()
    columns = lines[0].split()[1:]
    printed_rows = [line.split()[0] for line in lines[1:]]
    cells = table_of(rb)
    assert len(cells) == 49
    for line in lines[1:]:
        row, *values = line.split()
        for col, value in zip(columns, values, strict=True):
            assert cells[row, col] == value.upper(), (row, col)
    # The rules keep the printed order: PL's row first.
    first_rows = list(dict.fromkeys(r for r, _ in cells))
    assert first_rows == printed_rows
    assert "differs from the canonical" in rb.description


def test_paper_table1_is_not_the_canonical_table_and_mostly_follows_de() -> None:
    paper = table_of(load("paper_table1"))
    canonical = table_of(load("macvicar_whelan"))
    differing = [k for k in paper if paper[k] != canonical[k]]
    assert len(differing) > 20
    # Down each column (fixed de) the printed output barely moves; along rows it sweeps.
    index = {label: i for i, label in enumerate(LABELS)}
    spread_down = max(
        max(index[paper[r, c]] for r in LABELS) - min(index[paper[r, c]] for r in LABELS)
        for c in LABELS
    )
    spread_across = min(
        max(index[paper[r, c]] for c in LABELS) - min(index[paper[r, c]] for c in LABELS)
        for r in LABELS
    )
    assert spread_down <= 2 < spread_across == 6


def test_paper_table1_transposed_reads_the_printed_rows_as_de() -> None:
    rb = load("paper_table1_transposed")
    cells: dict[tuple[str, str], str] = {}
    for rule in rb.rules:
        a = rule.antecedent
        assert isinstance(a, Compound) and a.op == "and"
        terms = {p.variable: p.term for p in a.operands if isinstance(p, Proposition)}
        cells[terms["de"], terms["e"]] = rule.consequents[0].term
    lines = PAPER_TABLE_I.splitlines()
    columns = lines[0].split()[1:]
    assert len(cells) == 49
    for line in lines[1:]:
        row, *values = line.split()
        for col, value in zip(columns, values, strict=True):
            assert cells[row, col] == value.upper(), (row, col)  # printed row = de
    assert "transposed reading" in rb.description and rb.input_names == ("e", "de")


def test_paper_table1_transposed_is_the_printed_surface_with_inputs_swapped() -> None:
    from _mamdani_reference import reference

    printed, transposed = load("paper_table1"), load("paper_table1_transposed")
    rng = np.random.default_rng(7)
    points = [(0.0, 0.5), (0.5, 0.0), (-1.0, 1.0), *rng.uniform(-1.0, 1.0, (6, 2)).tolist()]
    for e, de in points:
        got = evaluate_point(transposed, {"e": e, "de": de})["du"]
        want = reference(printed, {"e": de, "de": e})  # independent fine-grid Mamdani
        assert want is not None and got == pytest.approx(want, abs=1e-6), (e, de)
    # What the transposition does near the origin: the printed table ignores e when de = 0
    # (no integral action), the transposed one ignores de when e = 0 (no proportional action).
    for x in (0.1, 0.3, 0.6):
        assert evaluate_point(printed, {"e": x, "de": 0.0})["du"] == pytest.approx(0, abs=1e-12)
        assert evaluate_point(transposed, {"e": 0.0, "de": x})["du"] == pytest.approx(0, abs=1e-12)
        assert evaluate_point(transposed, {"e": x, "de": 0.0})["du"] > 0.05


def expected_peak_output(k: int) -> float:
    """Centroid of output label k (-3..3) alone at full strength, clipped to [-1, 1].

    Inner labels are symmetric triangles (centroid = peak k/3); the outer ones are clipped to
    the half triangle between the range end and the neighbouring peak, whose centroid lies a
    third of the way in: 1 - (1/3)/3 = 8/9.
    """
    return k / 3 if abs(k) < 3 else float(np.sign(k)) * 8 / 9


def test_macvicar_whelan_at_the_label_peaks() -> None:
    rb = load("macvicar_whelan")
    ks = np.arange(-3, 4)
    e, de = np.meshgrid(ks / 3, ks / 3, indexing="ij")
    du = evaluate(rb, {"e": e, "de": de})["du"]
    for i in range(7):
        for j in range(7):
            k = max(-3, min(3, ks[i] + ks[j]))
            assert du[i, j] == pytest.approx(expected_peak_output(k), abs=1e-12)


def test_macvicar_whelan_is_odd_monotonic_and_bounded() -> None:
    rb = load("macvicar_whelan")
    rng = np.random.default_rng(7)
    e, de = rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500)
    du = evaluate(rb, {"e": e, "de": de})["du"]
    mirrored = evaluate(rb, {"e": -e, "de": -de})["du"]
    np.testing.assert_allclose(du, -mirrored, atol=1e-12)
    assert np.all(np.abs(du) <= 1.0)
    # On the label-peak grid the surface is the table itself: non-decreasing in e and de.
    peaks = np.arange(-3, 4) / 3
    pe, pd = np.meshgrid(peaks, peaks, indexing="ij")
    at_peaks = evaluate(rb, {"e": pe, "de": pd})["du"]
    assert np.diff(at_peaks, axis=0).min() > -1e-12 and np.diff(at_peaks, axis=1).min() > -1e-12
    # Between the peaks, centroid over max-aggregated clipped sets is known to dip slightly
    # (e.g. du(-0.85, -1) < du(-0.9, -1) by 0.003, confirmed by a brute-force centroid);
    # the dips stay below 2% of the output range.
    grid = np.linspace(-1, 1, 41)
    ee, dd = np.meshgrid(grid, grid, indexing="ij")
    surface = evaluate(rb, {"e": ee, "de": dd})["du"]
    assert np.diff(surface, axis=0).min() > -0.04
    assert np.diff(surface, axis=1).min() > -0.04
    assert surface[-1, -1] - surface[0, 0] == pytest.approx(16 / 9)


@pytest.mark.parametrize("name", ["macvicar_whelan", "paper_table1", "gaussian5", "three_input"])
def test_nan_input_gives_nan_never_a_correction(name: str) -> None:
    rb = load(name)
    point = {n: 0.2 for n in rb.input_names}
    point[rb.input_names[0]] = float("nan")
    assert all(np.isnan(v) for v in evaluate_point(rb, **point).values())


def test_gaussian5_uses_weights_product_and_bounded_sum() -> None:
    rb = load("gaussian5")
    assert {t.shape for v in rb.inputs for t in v.terms} == {"gaussian"}
    assert all(t.is_piecewise_linear for t in rb.outputs[0].terms)
    assert rb.operators.and_ == "product" and rb.operators.aggregation == "bounded_sum"
    assert any(r.weight < 1.0 for r in rb.rules)
    # A PI-like surface: positive errors push positive, zero at the origin (by symmetry).
    assert evaluate_point(rb, e=0.0, de=0.0)["du"] == pytest.approx(0.0, abs=1e-12)
    assert evaluate_point(rb, e=0.8, de=0.8)["du"] > 0.5
    assert evaluate_point(rb, e=-0.8, de=-0.8)["du"] < -0.5


def test_three_input_uses_or_not_and_two_outputs() -> None:
    rb = load("three_input")
    assert len(rb.inputs) == 3 and len(rb.outputs) == 2
    ops: set[str] = set()
    negated = False

    def walk(expr: Compound | Proposition) -> None:
        nonlocal negated
        if isinstance(expr, Compound):
            ops.add(expr.op)
            for o in expr.operands:
                walk(o)
        else:
            negated |= expr.negated

    for rule in rb.rules:
        walk(rule.antecedent)
    assert ops == {"and", "or"} and negated
    assert any(len(r.consequents) == 2 for r in rb.rules)
    smooth = evaluate_point(rb, e=0.0, de=0.0, r=0.05)
    rough = evaluate_point(rb, e=0.0, de=0.0, r=0.95)
    assert smooth["dv"] > 0 > rough["dv"]  # speed up on smooth stock, slow down on rough
