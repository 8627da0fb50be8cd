"""``fuzzkit eval --explain`` and ``fuzzkit.explain``: why an output is what it is, checked by hand
and by numeric integration of the aggregated set."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import fuzzkit
from fuzzkit.cli import main
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import evaluate_point

POINT = {"e": 0.25, "de": -0.1}


def _tri(y: np.ndarray, peak: float, half: float = 1.0 / 3.0) -> np.ndarray:
    return np.clip(1.0 - np.abs(y - peak) / half, 0.0, 1.0)


def test_memberships_and_strengths_by_hand_on_macvicar_whelan() -> None:
    x = fuzzkit.explain(load("macvicar_whelan"), POINT)
    e, de = x.inputs
    # triangles of half width 1/3 centred on k/3: e = 0.25 is 1/4 ZR, 3/4 PS; de = -0.1 is
    # 0.3 NS, 0.7 ZR
    assert {k: v for k, v in e.memberships.items() if v > 0} == pytest.approx(
        {"ZR": 0.25, "PS": 0.75}
    )
    assert {k: v for k, v in de.memberships.items() if v > 0} == pytest.approx(
        {"NS": 0.3, "ZR": 0.7}
    )
    # min of the two, consequents of the saturated-sum table out = clamp(i_e + i_de)
    fired = {(r.text, round(r.strength, 12)) for r in x.rules}
    assert fired == {
        ("if e is PS and de is ZR then du is PS", 0.7),
        ("if e is PS and de is NS then du is ZR", 0.3),
        ("if e is ZR and de is NS then du is NS", 0.25),
        ("if e is ZR and de is ZR then du is ZR", 0.25),
    }
    assert [r.strength for r in x.rules] == sorted((r.strength for r in x.rules), reverse=True)


def test_the_aggregated_set_matches_one_built_by_hand_and_integrates_to_evals_output() -> None:
    rb = load("macvicar_whelan")
    (out,) = fuzzkit.explain(rb, POINT).outputs
    # by hand: NS cut at 0.25, ZR at max(0.3, 0.25), PS at 0.7 (min implication, max aggregation)
    hand = np.maximum.reduce(
        [
            np.minimum(_tri(out.y, -1 / 3), 0.25),
            np.minimum(_tri(out.y, 0.0), 0.3),
            np.minimum(_tri(out.y, 1 / 3), 0.7),
        ]
    )
    np.testing.assert_allclose(out.mu, hand, atol=1e-12)
    y = np.linspace(-1.0, 1.0, 400_001)  # finer than the explanation's own samples
    mu = np.interp(y, out.y, out.mu)
    centroid = np.trapezoid(mu * y, y) / np.trapezoid(mu, y)
    assert out.value == evaluate_point(rb, POINT)["du"]
    assert centroid == pytest.approx(out.value, abs=2e-6)


@pytest.mark.parametrize(
    ("name", "point"),
    [
        ("gaussian5", {"e": 0.3, "de": 0.7}),
        ("paper_table1", {"e": -0.4, "de": 0.05}),
        ("temperature_pd", {"e": 3.0, "de": -1.0}),
    ],
)
def test_centroid_of_the_set_equals_the_engine_on_other_rule_bases(
    name: str, point: dict[str, float]
) -> None:
    rb = load(name)
    for out in fuzzkit.explain(rb, point).outputs:
        var = rb.output(out.name)
        centroid = np.trapezoid(out.mu * out.y, out.y) / np.trapezoid(out.mu, out.y)
        assert centroid == pytest.approx(out.value, abs=1e-5 * (var.high - var.low))


def test_sugeno_terms_are_their_linear_laws_at_the_point() -> None:
    x = fuzzkit.explain(load("sugeno_pi"), {"e": 0.3, "de": 1.4})
    (out,) = x.outputs
    assert x.inputs[1].seen == 1.0  # clamped to the range
    # gentle = 0.2 e + 0.5 de, firm = 0.6 e + 1.0 de, at the clamped de = 1
    assert out.term_values == pytest.approx({"hold": 0.0, "gentle": 0.56, "firm": 1.18})
    strengths = {r.text.rsplit(" ", 1)[-1]: r.strength for r in x.rules}
    assert strengths == pytest.approx({"gentle": 0.7, "firm": 0.3})  # e is 0.7 Z, 0.3 P
    assert out.value == pytest.approx(0.7 * 0.56 + 0.3 * 1.18)


def test_cli_text_json_and_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["eval", "macvicar_whelan", "-i", "e=0.25", "-i", "de=-0.1", "--explain"]
    png = tmp_path / "why.png"
    assert main([*args, "--png", str(png)]) == 0
    text = capsys.readouterr().out
    assert "e = 0.25: ZR 0.25, PS 0.75" in text
    assert "rules that fire: 4 of 49" in text
    assert "  0.7000  #32: if e is PS and de is ZR then du is PS" in text
    assert f"du = {evaluate_point(load('macvicar_whelan'), POINT)['du']!r} (centroid)" in text
    assert png.read_bytes().startswith(b"\x89PNG")
    assert main([*args, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [r["strength"] for r in data["rules"]] == pytest.approx([0.7, 0.3, 0.25, 0.25])
    (out,) = data["outputs"]
    y, mu = np.array(out["aggregated_set"]["y"]), np.array(out["aggregated_set"]["mu"])
    assert np.trapezoid(mu * y, y) / np.trapezoid(mu, y) == pytest.approx(out["value"], abs=1e-5)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--png", "x.png"], "give --explain too"),
        (["--explain", "-i", "e=nan"], "is NaN"),
        (["--explain", "--png", "x.jpg"], "ending in .png"),
    ],
)
def test_cli_explain_refusals(
    extra: list[str], match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["eval", "macvicar_whelan", "-i", "de=0", *extra]
    if "-i" not in extra:
        args += ["-i", "e=0"]
    assert main(args) == 2
    assert match in capsys.readouterr().err
