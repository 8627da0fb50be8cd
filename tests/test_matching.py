"""Tests of small-signal-matched gains and the comparison protocols of ``fuzzkit compare``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.control.controllers import FuzzyPI, Surface, saturated_sum_surface
from fuzzkit.control.loop_rulebase import exact_surface
from fuzzkit.errors import ConfigError
from fuzzkit.formats.registry import load, loads
from fuzzkit.studies.experiments import DEFAULT_GAINS
from fuzzkit.studies.matching import matched_fuzzy_gains, measure_slopes, small_signal_ratios
from fuzzkit.studies.protocol import protocol_gains


def _simpson_piecewise(knots: list[float], mu: list[float]) -> tuple[float, float]:
    """Exact area and first moment of a piecewise-linear ``mu`` given at ``knots``.

    On each linear piece ``y*mu(y)`` is quadratic, so Simpson's rule is exact.
    """
    area = moment = 0.0
    for (a, fa), (b, fb) in zip(
        zip(knots, mu, strict=True), zip(knots[1:], mu[1:], strict=True), strict=False
    ):
        m, fm = 0.5 * (a + b), 0.5 * (fa + fb)
        area += (b - a) * (fa + fb) / 2.0
        moment += (b - a) / 6.0 * (a * fa + 4.0 * m * fm + b * fb)
    return area, moment


def mw_closed_form(e: float) -> float:
    """Centroid MacVicar-Whelan ``F(e, 0)`` for ``0 <= e <= 1/6`` in closed form.

    With ``a = 3e``: ZR fires at ``1 - a`` and PS at ``a`` (the only rules on de = ZR);
    min-implication, max-aggregation of output triangles of half-width 1/3 give the polygon
    below (breakpoints worked out by hand), whose centroid is exact.
    """
    a = 3.0 * e
    knots = [-1 / 3, -a / 3, a / 3, (1 - a) / 3, (2 - a) / 3, 2 / 3]
    mu = [0.0, 1 - a, 1 - a, a, a, 0.0]
    area, moment = _simpson_piecewise(knots, mu)
    return moment / area


@pytest.fixture(scope="module")
def mw_surface() -> Surface:
    return exact_surface(load("macvicar_whelan"))


def test_engine_matches_the_closed_form_near_the_origin(mw_surface: Surface) -> None:
    # The figure quoted in the issue: F(0.02, 0) = 0.0278 (a secant slope of 1.39).
    assert mw_closed_form(0.02) == pytest.approx(0.027830, abs=5e-6)
    for e in (1e-4, 0.01, 0.02, 0.1, 1 / 6):
        assert mw_surface(e, 0.0) == pytest.approx(mw_closed_form(e), abs=1e-9)


def test_measured_slope_is_the_closed_form_limit(mw_surface: Surface) -> None:
    # d/de of the closed form at 0: the PS strip adds area e at centroid 1/2 to the ZR
    # triangle of area 1/3, so F ~ (e/2) / (1/3) = 1.5 e. The secant at 0.02 (1.39) is not it.
    s = measure_slopes(mw_surface)
    assert s.e == pytest.approx(1.5, abs=1e-4)
    assert s.de == pytest.approx(1.5, abs=1e-4)  # the table is symmetric in e and de
    assert s.e == pytest.approx(mw_closed_form(1e-7) / 1e-7, abs=1e-4)


def test_saturated_sum_has_unit_slopes() -> None:
    s = measure_slopes(saturated_sum_surface)
    assert (s.e, s.de) == (pytest.approx(1.0, abs=1e-9), pytest.approx(1.0, abs=1e-9))


def test_matched_gains_satisfy_the_matching_equations(mw_surface: Surface) -> None:
    pi = {"kp": 3e-5, "ki": 2e-5}
    m = matched_fuzzy_gains(mw_surface, pi)
    g = m.gains
    assert g["ki"] == 0.05  # the error's full scale is kept
    assert g["kx"] * g["ki"] * 1.5 == pytest.approx(2e-5, rel=1e-4)
    assert g["kx"] * g["kp"] * 1.5 == pytest.approx(3e-5, rel=1e-4)
    assert m.unmatched == ()
    assert g["u_min"] == -0.05 and g["u_max"] == 0.05


def _responses(
    surface: Surface, fuzzy: dict[str, float], measured: list[float]
) -> tuple[list[float], list[float]]:
    """du per period of the PI (closed form, eq. 9) and of the fuzzy-PI on one force series."""
    kp, ki, sp = 4e-5, 1e-5, 10.0
    fz = FuzzyPI(surface, fuzzy["kp"], fuzzy["ki"], fuzzy["kx"])
    pi_du, fz_du = [], []
    e_prev = None
    for m in measured:
        e = sp - m
        de = 0.0 if e_prev is None else e - e_prev
        e_prev = e
        pi_du.append(kp * de + ki * e)
        before = fz.u
        fz_du.append(fz.step(sp, m) - before)
    return pi_du, fz_du


#: A small error dying away (e > 0, de <= 0): errors of 3-15 mN, inside the origin's cell.
CONVERGING = [9.985, 9.99, 9.993, 9.995, 9.997, 9.998]


def test_matched_fuzzy_pi_responds_like_the_pi_while_the_error_shrinks(mw_surface: Surface) -> None:
    m = matched_fuzzy_gains(mw_surface, {"kp": 4e-5, "ki": 1e-5})
    pi_du, fz_du = _responses(mw_surface, m.gains, CONVERGING)
    assert all(abs(d) > 1e-9 for d in pi_du)
    for a, b in zip(pi_du, fz_du, strict=True):
        # normalised inputs below 3e-3: the surface's curvature (F ~ 1.5x - 6x|x|) costs < 2 %
        assert b == pytest.approx(a, rel=0.02)
    # The hand-set defaults are not matched: their fuzzy-PI answers 1.5x the PI.
    _, default_du = _responses(mw_surface, {"kp": 0.2, "ki": 0.05, "kx": 2e-4}, CONVERGING)
    for a, b in zip(pi_du, default_du, strict=True):
        assert b / a == pytest.approx(1.5, rel=0.02)


def test_matched_fuzzy_pi_has_more_gain_while_the_error_grows(mw_surface: Surface) -> None:
    # A step away from the set point: on the step sample e and de have the same sign, and the
    # rule (PS, PS) -> PM fires too. Worked by hand like mw_closed_form, to first order:
    # F(x, y) = 1.5 max(x, y) + 2.5 min(x, y) for x, y >= 0 (PS strip at max, PM strip at min,
    # centroids 1/2 and 5/6 over the ZR triangle's area 1/3), against the PI's 1.5 (x + y).
    m = matched_fuzzy_gains(mw_surface)
    g = m.gains
    step = [10.0, 9.99, 9.99, 9.99]
    pi_du, fz_du = _responses(mw_surface, g, step)
    x, y = g["ki"] * 0.01, g["kp"] * 0.01
    expected = g["kx"] * (1.5 * max(x, y) + 2.5 * min(x, y))
    assert fz_du[1] == pytest.approx(expected, rel=0.02)
    assert fz_du[1] / pi_du[1] == pytest.approx(expected / (g["kx"] * 1.5 * (x + y)), rel=0.02)
    assert fz_du[1] > 1.1 * pi_du[1]
    for a, b in zip(pi_du[2:], fz_du[2:], strict=True):  # de = 0 again: matched
        assert b == pytest.approx(a, rel=0.02)


def test_paper_table1_cannot_match_ki() -> None:
    surface = exact_surface(load("paper_table1"))
    s = measure_slopes(surface)
    assert abs(s.e) < 1e-6  # Table I as printed: no dependence on e at the origin
    assert s.de == pytest.approx(1.5, abs=1e-4)
    m = matched_fuzzy_gains(surface)
    assert len(m.unmatched) == 1 and m.unmatched[0].startswith("ki not matched")
    assert m.gains["kx"] == 2e-4  # kept
    assert m.gains["kx"] * m.gains["kp"] * s.de == pytest.approx(4e-5, rel=1e-9)


def test_zero_surface_cannot_be_matched() -> None:
    with pytest.raises(ConfigError, match="nothing to match"):
        matched_fuzzy_gains(lambda e, de: 0.0)


@pytest.mark.parametrize(
    "args, match",
    [
        (("tuned", None), "needs --gains"),
        (("fastest", None), "unknown protocol"),
    ],
)
def test_protocol_errors(mw_surface: Surface, args: tuple[str, None], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        protocol_gains(args[0], mw_surface, args[1])


def test_tuned_protocol_needs_both_controllers(mw_surface: Surface, tmp_path: Path) -> None:
    f = tmp_path / "g.yaml"
    f.write_text("pi:\n  kp: 3.0e-5\n  ki: 1.0e-5\n")
    with pytest.raises(ConfigError, match="no gains for fuzzy-pi"):
        protocol_gains("tuned", mw_surface, f)
    f.write_text(f.read_text() + "fuzzy-pi:\n  kp: 0.3\n  ki: 0.06\n  kx: 1.0e-4\n")
    chosen = protocol_gains("tuned", mw_surface, f)
    assert chosen["fuzzy-pi"].gains["kx"] == 1e-4 and chosen["pi"].gains["kp"] == 3e-5
    assert "kept" not in chosen["pi"].source
    # A file where tuning kept the defaults says so in the gains line.
    f.write_text(
        "pi:\n  gains: {kp: 4.0e-5, ki: 1.0e-5}\n  provenance: {kept_defaults: true}\n"
        "fuzzy-pi:\n  kp: 0.3\n  ki: 0.06\n  kx: 1.0e-4\n"
    )
    chosen = protocol_gains("tuned", mw_surface, f)
    assert chosen["pi"].source.endswith("(the search kept the default gains)")
    assert "kept" not in chosen["fuzzy-pi"].source


def test_cli_compare_protocol_prints_the_gains(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", "E1", "--protocol", "matched"]) == 0
    out = capsys.readouterr().out
    assert "protocol: matched" in out
    assert "pi: kp=4e-05, ki=1e-05 (default)" in out
    assert "fuzzy-pi: kp=0.2, ki=0.05, kx=0.0001333 (matched to pi" in out
    assert main(["compare", "E1", "--protocol", "default", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    fz = next(r for r in rows if r["controller"] == "fuzzy-pi")
    assert fz["protocol"] == "default" and fz["gains"]["kx"] == 2e-4


#: A Sugeno fuzzy-PI whose slopes at the origin are worked by hand: on the axis de = 0 with
#: 0 < e < 1 only (Z, Z) -> 0 and (P, Z) -> 0.5 fire, with product strengths 1 - e and e, so
#: the weighted average is F = 0.5 e (slope 0.5 along e); on e = 0 likewise F = 2 de.
HAND_SLOPES_YAML = """
name: hand_slopes
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
  de: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  du:
    range: [-2, 2]
    terms:
      zero: {shape: constant, value: 0}
      half_up: {shape: constant, value: 0.5}
      half_down: {shape: constant, value: -0.5}
      two_up: {shape: constant, value: 2}
      two_down: {shape: constant, value: -2}
operators: {and: product, or: max, implication: min, aggregation: max}
defuzzifier: weighted_average
rules:
  - {if: {e: Z, de: Z}, then: {du: zero}}
  - {if: {e: P, de: Z}, then: {du: half_up}}
  - {if: {e: N, de: Z}, then: {du: half_down}}
  - {if: {e: Z, de: P}, then: {du: two_up}}
  - {if: {e: Z, de: N}, then: {du: two_down}}
  - {if: {e: P, de: P}, then: {du: two_up}}
  - {if: {e: N, de: N}, then: {du: two_down}}
  - {if: {e: P, de: N}, then: {du: zero}}
  - {if: {e: N, de: P}, then: {du: zero}}
"""


def test_small_signal_ratios_follow_the_rule_base_in_use(mw_surface: Surface) -> None:
    # DEFAULT_GAINS: Kx*Kp = kp and Kx*Ki = ki, so the ratios are the slopes at the origin
    # (proportional along de, integral along e): 1.5 for MacVicar-Whelan (the closed form
    # above: (e/2) / (1/3)), 2 and 0.5 for the hand system, 0 along e for the paper's table
    hand = exact_surface(loads(HAND_SLOPES_YAML))
    assert hand(0.01, 0.0) == pytest.approx(0.005, abs=1e-12)  # the hand F = 0.5 e
    cases = [
        (mw_surface, (1.5, 1.5)),
        (hand, (2.0, 0.5)),
        (exact_surface(load("paper_table1")), (1.5, 0.0)),
    ]
    for surface, (p, i) in cases:
        got = small_signal_ratios(surface)
        assert got == (pytest.approx(p, rel=1e-4), pytest.approx(i, rel=1e-4, abs=1e-9))
    # other gains scale the ratios: Kx doubled doubles both
    doubled = small_signal_ratios(hand, {"kx": 2 * DEFAULT_GAINS["fuzzy-pi"]["kx"]})
    assert doubled == (pytest.approx(4.0, rel=1e-4), pytest.approx(1.0, rel=1e-4))
