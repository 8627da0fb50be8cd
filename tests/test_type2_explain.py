"""``fuzzkit eval --explain`` on an interval type-2 rule base: the firing intervals, both
output sets and the centroid interval, against the textbook brute force of
tests/_type2_reference.py (text, JSON and the PNG)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from _type2_reference import firing_intervals, output_sets

from fuzzkit.cli import main
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.type2_model import Type2RuleBase

POINT = {"e": 0.3, "de": -0.2}
ARGS = ["eval", "macvicar_whelan_it2", "-i", "e=0.3", "-i", "de=-0.2", "--explain"]


def _rb() -> Type2RuleBase:
    rb = load("macvicar_whelan_it2")
    assert isinstance(rb, Type2RuleBase)
    return rb


def test_json_gives_the_firing_intervals_both_sets_and_the_interval(
    capsys: pytest.CaptureFixture[str],
) -> None:
    rb = _rb()
    assert main([*ARGS, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    want = firing_intervals(rb, POINT)
    fired = {r["index"]: r["firing_interval"] for r in data["rules"]}
    assert set(fired) == {k + 1 for k, (_, up) in enumerate(want) if up > 0.0}
    for index, (lo, up) in fired.items():
        assert (lo, up) == pytest.approx(want[index - 1], abs=1e-15)
    e = data["inputs"][0]
    assert e["lower_memberships"]["PS"] == pytest.approx(0.8 * (1 - abs(0.3 - 0.3333) / 0.25))
    (out,) = data["outputs"]
    y = np.array(out["aggregated_set"]["y"])
    upper, lower = output_sets(rb, POINT, y)
    np.testing.assert_allclose(out["aggregated_set"]["mu"], upper, atol=1e-12)
    np.testing.assert_allclose(out["lower_set"]["mu"], lower, atol=1e-12)
    (y_l, y_r) = Engine(rb).centroid_intervals({k: [v] for k, v in POINT.items()})["du"]
    assert out["interval"] == [float(y_l[0]), float(y_r[0])]
    assert out["value"] == pytest.approx(0.5 * (y_l[0] + y_r[0]), abs=1e-15)


def test_text_lists_each_rule_with_its_interval(capsys: pytest.CaptureFixture[str]) -> None:
    want = firing_intervals(_rb(), POINT)
    assert main(ARGS) == 0
    text = capsys.readouterr().out
    shown = {
        int(k): (float(lo), float(up))
        for lo, up, k in re.findall(r"^  \[([\d.]+), ([\d.]+)\]  #(\d+): if ", text, re.M)
    }
    assert set(shown) == {k + 1 for k, (_, up) in enumerate(want) if up > 0.0}
    for k, interval in shown.items():
        assert interval == pytest.approx(want[k - 1], abs=5.1e-5)  # printed to 4 decimals
    assert "e = 0.3: ZR [0, 0.25], PS [0.69344, 0.91675], PM [0, 0.08325]" in text
    assert "du: lower set; term levels" in text and "centroid interval [" in text


def test_png_draws_the_footprint_and_the_interval(tmp_path: Path) -> None:
    from matplotlib.collections import PolyCollection

    from fuzzkit.fuzzy.explain import explain
    from fuzzkit.viz.explain_plot import explanation_figure

    rb = _rb()
    data = explain(rb, POINT)
    fig = explanation_figure(rb, data)
    last = fig.axes[-1]  # the output's aggregate cell
    assert len([c for c in last.collections if isinstance(c, PolyCollection)]) == 2
    dotted = [ln.get_xdata()[0] for ln in last.lines if ln.get_linestyle() == ":"]
    assert dotted == list(data.outputs[0].interval or ())
    png = tmp_path / "why.png"
    assert main([*ARGS, "--png", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
