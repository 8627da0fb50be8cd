"""The loop's rest point comes first (issue 29 item 1): a surface that is not 0 at zero error
and change rests off the set point, and no cell is certified as settling there."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fuzzkit.analysis.equilibrium import fuzzy_equilibrium, zero_set
from fuzzkit.analysis.fuzzy_bounds import gradient_bounds
from fuzzkit.cli import main

OFFSET = Path(__file__).parent / "data" / "stability" / "offset.yaml"


@pytest.mark.parametrize(
    ("surface", "intervals"),
    [
        (lambda x: 1.5 * x, [(0.0, 0.0)]),
        (lambda x: x + 0.2, [(-0.2, -0.2)]),
        (lambda x: np.tanh(3 * (x - 0.31)), [(0.31, 0.31)]),
        (lambda x: (x - 0.5) * (x + 0.25), [(-0.25, -0.25), (0.5, 0.5)]),
        (lambda x: x + 2.0, []),
        # a dead band: F(x, 0) = 0 for |x| <= 0.125 (0.125 is a sample: 2048 steps of 1/1024)
        (lambda x: np.sign(x) * np.maximum(np.abs(x) - 0.125, 0.0), [(-0.125, 0.125)]),
    ],
)
def test_the_zero_set_of_closed_forms(surface, intervals):
    zs = zero_set(surface)
    assert len(zs.intervals) == len(intervals)
    for (lo, hi), (elo, ehi) in zip(zs.intervals, intervals, strict=True):
        assert lo == pytest.approx(elo, abs=1e-12)
        assert hi == pytest.approx(ehi, abs=1e-12)
    assert zs.f00 == pytest.approx(float(surface(np.array([0.0]))[0]), abs=1e-15)


def test_the_offset_example_rests_4_n_above_the_set_point():
    # F(x, 0) = x + 0.2 is 0 at x = Ki*e = -0.2; Ki = 0.05 per N: e = -4 N, force 14 N
    eq = fuzzy_equilibrium(zero_set(lambda x: x + 0.2), 0.05, 10.0)
    assert not eq.at_setpoint
    assert eq.offset_n == pytest.approx(4.0, abs=1e-9)
    assert "14 N, 4 N above the set point 10 N" in eq.why


def test_a_lone_zero_at_the_origin_is_the_set_point_and_a_dead_band_is_not():
    assert fuzzy_equilibrium(zero_set(lambda x: 1.5 * x), 0.05, 10.0).at_setpoint
    dead = fuzzy_equilibrium(
        zero_set(lambda x: np.sign(x) * np.maximum(np.abs(x) - 0.125, 0.0)), 0.05, 10.0
    )
    assert not dead.at_setpoint
    # the force can rest anywhere within 0.125 / 0.05 = 2.5 N of the set point
    assert dead.band_n == pytest.approx((-2.5, 2.5))
    none = fuzzy_equilibrium(zero_set(lambda x: x + 2.0), 0.05, 10.0)
    assert not none.at_setpoint and math.isnan(none.offset_n)
    assert "no rest point" in none.why


def test_gradient_bounds_are_taken_around_the_rest_point():
    # F = x + y + 0.2 except for a steeper patch far from the rest point (-0.2, 0): a box of
    # 0.3 around the rest point does not reach it, a box around the origin of 0.7 does
    bp = np.linspace(-1.0, 1.0, 21)
    x, y = np.meshgrid(bp, bp, indexing="ij")
    values = x + y + 0.2 + 4.0 * np.maximum(x - 0.5, 0.0)
    splits = np.zeros((20, 20), dtype=np.int64)
    around = gradient_bounds(bp, bp, values, splits, 0.3, centre=-0.2)
    assert around.a_range == pytest.approx((1.0, 1.0))
    assert around.centre == -0.2 and around.rho == pytest.approx(0.3)
    assert gradient_bounds(bp, bp, values, splits, 0.7).a_range == pytest.approx((1.0, 5.0))
    # the box stays inside the universe: at most 1 - |centre| = 0.8 around -0.2
    assert gradient_bounds(bp, bp, values, splits, 1.0, centre=-0.2).rho == pytest.approx(0.8)


def test_the_offset_rule_base_is_certified_nowhere_and_the_output_says_why(capsys):
    # issue 29's example: before, 6 of 6 cells were certified (all oscillate in simulation)
    argv = ["stability", "regulate", "--controller", "fuzzy-pi", "--rulebase", str(OFFSET)]
    argv += ["--plant", "arm6", "--stiffness", "5,10,20", "--latency", "0:0,1:1"]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rest = data["model"]["equilibrium"]
    assert rest["at_setpoint"] is False
    assert rest["offset_n"] == pytest.approx(4.0, abs=1e-9)  # found on the exact surface
    assert data["model"]["fuzzy"]["around_scaled_error"] == pytest.approx(-0.2, abs=1e-9)
    assert len(data["cells"]) == 6
    for cell in data["cells"]:
        assert cell["certified"] is False
        assert "4 N above the set point" in cell["why_not_certified"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "no cell is certified as settling at the set point" in text
    assert "certified 0 of 6 cells" in text


@pytest.mark.slow
def test_the_offset_loop_settles_where_the_rest_point_says_in_simulation():
    # independent of the certificate: the compiled loop's force, averaged over the last 0.5 s
    from fuzzkit.analysis.regulation import regulation_experiment
    from fuzzkit.loop.compiled_loop import run_compiled
    from fuzzkit.studies.experiments import with_stiffness

    exp = with_stiffness(regulation_experiment(), 1.0e4)
    result = run_compiled(exp, "arm6", "fuzzy-pi", rulebase=str(OFFSET), latency=(0, 0), seed=0)
    tail = result.force_true[result.t >= result.t[-1] - 0.5, 2]
    assert float(np.mean(tail)) == pytest.approx(14.0, abs=0.3)
