"""The set point is the only rest point in the certified region (issue 40 item 2): proven with
sound bounds of F(x, 0) (fuzzkit.analysis.rest_points), checked against dense evaluations,
and a rule base with a second and third rest point next to the set point is refused."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis.region import certify_region
from fuzzkit.analysis.regulation import scenario
from fuzzkit.analysis.rest_points import prove_exact, prove_table
from fuzzkit.codegen.table_search import make_table
from fuzzkit.control.loop_rulebase import load_loop_rulebase
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.loop.compiled.table import TableArrays, table2, table_arrays

NARROW = str(Path(__file__).parent / "data" / "stability" / "narrow_rest.yaml")


def _line(rb, xs):
    a, b = rb.inputs[0].name, rb.inputs[1].name
    return np.asarray(evaluate(rb, {a: xs, b: np.zeros_like(xs)})[rb.outputs[0].name])


def _sign_changes(xs, fs):
    """Midpoints of dense intervals where F changes sign or vanishes (x = 0 left out)."""
    s = np.sign(fs)
    k = np.nonzero(s[:-1] * s[1:] <= 0)[0]
    mids = 0.5 * (xs[k] + xs[k + 1])
    return mids[np.abs(mids) > 1e-3]


@pytest.mark.parametrize(
    "name",
    [
        "macvicar_whelan",
        NARROW,
        # the others in make verify (a proof and 200,001 engine points each)
        pytest.param("gaussian5", marks=pytest.mark.verify),
        pytest.param("tests/data/user/renamed.yaml", marks=pytest.mark.verify),
        pytest.param("tests/data/user/user_pi.fis", marks=pytest.mark.verify),
        pytest.param("tests/data/user/nonuniform5.yaml", marks=pytest.mark.verify),
    ],
)
def test_the_proof_agrees_with_a_dense_evaluation(name):
    rb = replace(load_loop_rulebase(name), out_of_range="clamp")
    proof = prove_exact(rb, -1.0, 1.0)
    xs = np.linspace(-1.0, 1.0, 200_001)
    # every zero the dense grid sees off the set point (somewhere between two neighbouring
    # samples: the proof's intervals can be narrower than the grid's step) meets a place
    # where the proof says one may be
    step = xs[1] - xs[0]
    for x in _sign_changes(xs, _line(rb, xs)):
        lo, hi = x - step / 2, x + step / 2
        assert any(a <= hi and lo <= b for a, b in proof.others) or (
            proof.near[0] <= hi and lo <= proof.near[1]
        )
    # and the unresolved neighbourhood is small: a few thousandths of the scaled range
    assert proof.near[1] - proof.near[0] < 0.01


def test_the_narrow_feature_has_two_more_rest_points_and_the_others_none():
    narrow = prove_exact(replace(load_loop_rulebase(NARROW), out_of_range="clamp"), -1.0, 1.0)
    assert len(narrow.others) == 2
    assert all(0.03 < a < b < 0.05 for a, b in narrow.others)
    mw = prove_exact(replace(load_loop_rulebase("macvicar_whelan"), out_of_range="clamp"), -1, 1)
    assert mw.proven


@pytest.mark.parametrize("offset", [0.0, 0.013])  # de = 0 on a row of nodes, or across cells
def test_the_table_proof_finds_the_zeros_of_a_closed_form_table(offset):
    # F = x (x - 0.3) (x + 0.5) - y at the nodes: on de = 0 the table interpolates a cubic
    # whose zeros -0.5, 0 and 0.3 are nodes of x
    bp0 = np.linspace(-1.0, 1.0, 41)
    bp1 = np.linspace(-1.0, 1.0, 41) + offset
    bp1[0], bp1[-1] = -1.0, 1.0
    xx, yy = np.meshgrid(bp0, bp1, indexing="ij")
    values = xx * (xx - 0.3) * (xx + 0.5) - yy
    rng = np.random.default_rng(1)
    splits = rng.integers(0, 2, (40, 40))
    proof = prove_table(TableArrays(bp0, bp1, values, splits, "cubic"), -1.0, 1.0)
    xs = np.linspace(-1.0, 1.0, 4001)
    fs = np.array([table2(bp0, bp1, values, splits, float(x), 0.0) for x in xs])
    for x in _sign_changes(xs, fs):
        assert any(a <= x <= b for a, b in proof.others)
    for a, b in proof.others:
        inside = (xs >= a) & (xs <= b)
        assert np.any(fs[inside] <= 0.0) and np.any(fs[inside] >= 0.0)
    assert len(proof.others) == 2 if offset == 0.0 else len(proof.others) >= 2


@pytest.mark.verify
def test_the_table_proof_is_exact_on_the_table():
    rb = replace(load_loop_rulebase(NARROW), out_of_range="clamp")
    t = table_arrays(make_table(rb, number_type="double", resolution=161))
    proof = prove_table(t, -1.0, 1.0)
    xs = np.linspace(-1.0, 1.0, 4001)
    fs = np.array([table2(t.bp0, t.bp1, t.values, t.splits, float(x), 0.0) for x in xs])
    changes = _sign_changes(xs, fs)
    assert len(changes) >= 2  # the 161-point table resolves the narrow feature's zeros
    for x in changes:
        assert any(a <= x <= b for a, b in proof.others)
    for a, b in proof.others:
        inside = (xs >= a) & (xs <= b)
        assert np.any(np.sign(fs[inside]) <= 0) and np.any(np.sign(fs[inside]) >= 0)


def test_a_second_rest_point_in_the_region_refuses_every_cell():
    # the old check (is the zero nearest the origin 0?) certified all 6 cells with bounds
    # taken on a 129-point table that never sees the narrow feature
    region = certify_region(
        scenario("regulate"),
        "fuzzy-pi",
        "arm6",
        [5.0, 10.0, 20.0],
        [(0, 0), (1, 1)],
        rulebase=NARROW,
        fuzzy_region=0.2,
    )
    assert not any(c.certified for c in region.cells)
    assert any(c.stable for c in region.cells)  # Lyapunov alone would have certified
    for c in region.cells:
        assert "may vanish at Ki*e in [0.033" in c.why_not
        # the other rest point in N (Ki = 0.05): a 200,001-point grid of F(x, 0) changes sign
        # at x = 0.033441, e = 0.6688 N
        assert "(e = 0.669 to 0.669 N)" in c.why_not
    lone = region.model["fuzzy"]["lone_rest_point"]
    assert len(lone["possible_other_rest_points"]) == 2


def test_a_lone_rest_point_keeps_the_certificate():
    region = certify_region(
        scenario("regulate"), "fuzzy-pi", "arm6", [10.0], [(0, 0)], rulebase="macvicar_whelan"
    )
    assert region.cells[0].certified
    assert region.model["fuzzy"]["lone_rest_point"]["possible_other_rest_points"] == []
