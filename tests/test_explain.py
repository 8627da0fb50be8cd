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
        (["--explain", "--rules", "5"], "give --png too"),
        (
            ["--explain", "--png", "x.png", "--rules", "0"],
            "--rules: expected an integer from 1 to 64",
        ),
        (["--explain", "--png", "x.png", "--rules", "1000"], "from 1 to 64, got '1000'"),
    ],
)
def test_cli_explain_refusals(
    extra: list[str], match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["eval", "macvicar_whelan", "-i", "de=0", *extra]
    if "-i" not in extra:
        args += ["-i", "e=0"]
    try:
        code = main(args)
    except SystemExit as exc:  # a value argparse refuses (--rules)
        code = int(exc.code or 0)
    assert code == 2
    assert match in capsys.readouterr().err


# ------------------------------------------------- issue 33 item 6: the rule view (--png)


def _fills(ax: object) -> list[float]:
    """The top of every filled area (fill_between) drawn in ``ax``."""
    from matplotlib.collections import PolyCollection

    tops = []
    for art in ax.collections:  # type: ignore[attr-defined]
        if isinstance(art, PolyCollection):
            tops.append(float(max(v[:, 1].max() for v in (p.vertices for p in art.get_paths()))))
    return tops


def _fill_area(ax: object) -> float:
    """The area of the one filled region in ``ax`` (shoelace over its outline)."""
    from matplotlib.collections import PolyCollection

    (art,) = [a for a in ax.collections if isinstance(a, PolyCollection)]  # type: ignore[attr-defined]
    total = 0.0
    for path in art.get_paths():
        x, y = path.vertices[:, 0], path.vertices[:, 1]
        total += 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))
    return total


def test_the_rule_view_draws_each_fired_rule_as_computed_by_hand() -> None:
    from fuzzkit.fuzzy.rule_view import rule_rows
    from fuzzkit.viz.explain_plot import explanation_figure

    rb = load("macvicar_whelan")
    x = fuzzkit.explain(rb, POINT)
    rows = rule_rows(rb, x)
    # by hand (see above): strongest first, ties by rule number
    want = [("PS", 0.75, "ZR", 0.7, "PS"), ("PS", 0.75, "NS", 0.3, "ZR"),
            ("ZR", 0.25, "NS", 0.3, "NS"), ("ZR", 0.25, "ZR", 0.7, "ZR")]  # fmt: skip
    got = [
        (r.inputs["e"][0].term, r.inputs["e"][0].truth, r.inputs["de"][0].term,
         r.inputs["de"][0].truth, r.outputs["du"].term)
        for r in rows
    ]  # fmt: skip
    assert [g[::2] for g in got] == [w[::2] for w in want]
    assert [g[1::2] for g in got] == [pytest.approx(w[1::2]) for w in want]
    assert [r.strength for r in rows] == pytest.approx([0.7, 0.3, 0.25, 0.25])
    fig = explanation_figure(rb, x)
    axes = np.array(fig.axes).reshape(3, 5).T  # added column by column: e, de, du
    assert axes.shape == (5, 3)
    for r, (e_mu, de_mu, w) in enumerate([(0.75, 0.7, 0.7), (0.75, 0.3, 0.3),
                                          (0.25, 0.3, 0.25), (0.25, 0.7, 0.25)]):  # fmt: skip
        # each input term filled up to its membership, the consequent cut at the strength
        assert _fills(axes[r, 0]) == pytest.approx([e_mu])
        assert _fills(axes[r, 1]) == pytest.approx([de_mu])
        assert _fills(axes[r, 2]) == pytest.approx([w])
        # min implication: the triangle (base 2/3) cut flat at w, a trapezoid of area
        # (1/3) * (1 - (1 - w)^2); a scaled one (product) would be w/3
        assert _fill_area(axes[r, 2]) == pytest.approx((1 - (1 - w) ** 2) / 3, rel=1e-3)
        # the input value marked in every input cell
        assert [ln.get_xdata()[0] for ln in axes[r, 0].lines if ln.get_color() == "tab:red"] == [
            0.25
        ]
    # last row: the aggregated set (its peak is the strongest cut) and the defuzzified value
    assert _fills(axes[4, 2]) == pytest.approx([0.7])
    du = evaluate_point(rb, POINT)["du"]
    assert [ln.get_xdata()[0] for ln in axes[4, 2].lines if ln.get_color() == "tab:red"] == [du]
    texts = " ".join(t.get_text() for ax in fig.axes for t in ax.texts)
    assert "PS 0.75" in texts and "w 0.700" in texts and f"du = {du:.6g}" in texts


def test_the_rule_view_draws_the_top_n_of_many_firing_rules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from fuzzkit.viz.explain_plot import explanation_figure

    rb = load("gaussian5")  # gaussian terms: all 25 rules fire
    x = fuzzkit.explain(rb, {"e": 0.3, "de": -0.2})
    assert len(x.rules) == 25
    fig = explanation_figure(rb, x, top=5)
    assert len(fig.axes) == (5 + 1) * 3
    assert "the 5 strongest drawn" in fig._suptitle.get_text()
    labels = [ax.get_ylabel() for ax in fig.axes[:6]]
    assert labels == [f"rule {r.index}" for r in x.rules[:5]] + ["all"]
    png = tmp_path / "g5.png"
    args = ["eval", "gaussian5", "-i", "e=0.3", "-i", "de=-0.2", "--explain", "--png", str(png)]
    assert main([*args, "--rules", "5"]) == 0 and png.read_bytes().startswith(b"\x89PNG")
    capsys.readouterr()


def test_negated_and_untested_inputs_in_the_rule_view() -> None:
    from fuzzkit.fuzzy.rule_view import rule_rows

    rb = load("three_input")
    x = fuzzkit.explain(rb, {"e": 0.3, "de": -0.2, "r": 0.5})
    rows = {r.index: r for r in rule_rows(rb, x, top=64)}
    memberships = {i.name: i.memberships for i in x.inputs}
    negated = [(var, c) for r in rows.values() for var, cells in r.inputs.items()
               for c in cells if c.negated]  # fmt: skip
    assert negated
    for var, cell in negated:
        assert cell.truth == pytest.approx(1.0 - memberships[var][cell.term])
    assert any(len(r.inputs) < 3 for r in rows.values())  # a rule that leaves an input out


def test_explain_works_for_smooth_output_sets(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = Path(__file__).parent / "data" / "gaussian3x3.yaml"
    args = ["eval", str(path), "-i", "e=0.3", "-i", "de=-0.6", "--explain"]
    png = tmp_path / "why.png"
    assert main([*args, "--png", str(png)]) == 0
    text = capsys.readouterr().out
    value = evaluate_point(load(path), {"e": 0.3, "de": -0.6})["du"]
    assert f"du = {value!r} (centroid)" in text
    assert png.read_bytes().startswith(b"\x89PNG")
    assert main([*args, "--json"]) == 0
    (out,) = json.loads(capsys.readouterr().out)["outputs"]
    y, mu = np.array(out["aggregated_set"]["y"]), np.array(out["aggregated_set"]["mu"])
    # the set drawn is the set the engine integrated: its centroid is the value printed
    assert np.trapezoid(mu * y, y) / np.trapezoid(mu, y) == pytest.approx(value, abs=1e-5)
