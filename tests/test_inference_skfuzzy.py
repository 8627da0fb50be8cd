"""Cross-check of the shipped MacVicar-Whelan rule base against scikit-fuzzy (test-only peer).

scikit-fuzzy samples every set on a discrete universe, so it can only agree within its own
discretisation error: its aggregated set is the piecewise-linear interpolant of the samples,
which differs from the true set only in the few cells holding a kink, by at most the kink's
slope jump times ``h`` over a width ``h``: the area and moment errors, and so the centroid's,
are O(h^2). With h = 1e-3 we allow 5 h^2 (measured: about 1.1 h^2).
"""

from __future__ import annotations

import numpy as np
import pytest

import fuzzkit

skfuzzy = pytest.importorskip("skfuzzy")
ctrl = pytest.importorskip("skfuzzy.control")

STEP = 1e-3
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _skfuzzy_macvicar_whelan() -> object:
    rb = fuzzkit.load("macvicar_whelan")
    # round the universe so it ends exactly on the range end (else the outer peak is lost)
    universe = np.round(np.arange(-1.0, 1.0 + STEP / 2, STEP), 12)
    antecedents = {v.name: ctrl.Antecedent(universe, v.name) for v in rb.inputs}
    consequent = ctrl.Consequent(universe, "du", defuzzify_method="centroid")
    for var, sk in [*((v, antecedents[v.name]) for v in rb.inputs), (rb.outputs[0], consequent)]:
        for t in var.terms:
            p = list(t.params)
            if t.shape == "triangle":
                sk[t.name] = skfuzzy.trimf(universe, p)
            elif t.shape == "left_shoulder":
                sk[t.name] = skfuzzy.trapmf(universe, [p[0] - 1, p[0] - 1, p[0], p[1]])
            elif t.shape == "right_shoulder":
                sk[t.name] = skfuzzy.trapmf(universe, [p[0], p[1], p[1] + 1, p[1] + 1])
            else:  # pragma: no cover - the shipped file has only these shapes
                raise AssertionError(t.shape)
    rules = []
    for rule in rb.rules:
        a, b = rule.antecedent.operands  # type: ignore[union-attr]
        then = rule.consequents[0]
        rules.append(
            ctrl.Rule(
                antecedents[a.variable][a.term] & antecedents[b.variable][b.term],
                consequent[then.term],
            )
        )
    return ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules))


def _skfuzzy_eval(sim: object, points: np.ndarray) -> np.ndarray:
    out = []
    for e, de in points:
        sim.input["e"] = e  # type: ignore[attr-defined]
        sim.input["de"] = de  # type: ignore[attr-defined]
        sim.compute()  # type: ignore[attr-defined]
        out.append(sim.output["du"])  # type: ignore[attr-defined]
    return np.array(out)


def test_shipped_macvicar_whelan_agrees_with_scikit_fuzzy() -> None:
    sim = _skfuzzy_macvicar_whelan()
    rb = fuzzkit.load("macvicar_whelan")
    points = np.random.default_rng(3).uniform(-1, 1, size=(25, 2))
    ours = fuzzkit.evaluate(rb, {"e": points[:, 0], "de": points[:, 1]})["du"]
    err = np.abs(ours - _skfuzzy_eval(sim, points))
    assert err.max() < 5 * STEP**2, err.max()


def test_at_input_kinks_scikit_fuzzy_is_off_by_its_input_sampling() -> None:
    # at a label peak that falls between universe samples (k/3), scikit-fuzzy interpolates the
    # input membership linearly across the kink: an O(h) error in mu, so O(h) in the output
    sim = _skfuzzy_macvicar_whelan()
    rb = fuzzkit.load("macvicar_whelan")
    points = np.array([[1 / 3, -2 / 3], [0.0, 2 / 3], [-1 / 3, 0.1]])
    ours = fuzzkit.evaluate(rb, {"e": points[:, 0], "de": points[:, 1]})["du"]
    err = np.abs(ours - _skfuzzy_eval(sim, points))
    assert err.max() < 2 * STEP, err.max()
