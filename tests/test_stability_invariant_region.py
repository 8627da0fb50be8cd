"""``region_n``: the largest level set of the certificate's Lyapunov function inside the region
where its bounds hold (issue 29 item 3), against closed forms, an independent optimiser, samples
of the level set's boundary and switched trajectories checked with their own arithmetic."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from fuzzkit.analysis.inner_loop import identify
from fuzzkit.analysis.invariant_region import Slab, level_set, validity_slabs
from fuzzkit.analysis.loop_model import closed_loop_matrix, vertices
from fuzzkit.analysis.region import (
    SIGMA_MIN,
    axis_loop,
    certify_cell,
    effective_gains,
    fuzzy_part,
)
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.cli import main


def test_closed_forms():
    # P = I in 2-D, |x1| <= 1: gamma = 1; the rest state d (1, 1) has V = 2 d^2
    found = level_set(np.eye(2), [Slab(np.array([1.0, 0.0]), 1.0, "a")])
    assert found.gamma == pytest.approx(1.0)
    assert found.region_n == pytest.approx(math.sqrt(0.5))
    # P = diag(4, 1), |x1 + x2| <= 2: max (h'x)^2 over x'Px <= 1 is h'P^-1 h = 1.25
    slabs = [Slab(np.array([1.0, 1.0]), 2.0, "b"), Slab(np.array([0.0, 1.0]), 10.0, "c")]
    found = level_set(np.diag([4.0, 1.0]), slabs)
    assert found.gamma == pytest.approx(4.0 / 1.25)
    assert found.region_n == pytest.approx(math.sqrt(3.2 / 5.0))
    assert found.limited_by == "b"


def _cell(controller: str, stiffness: float, latency: tuple[int, int]):
    exp = regulation_experiment()
    inner = identify("arm6")
    fuzzy = fuzzy_part("macvicar_whelan") if controller == "fuzzy-pi" else None
    cell = certify_cell(
        exp, controller, None, inner, fuzzy, stiffness, latency, SIGMA_MIN, 0.1, None
    )
    assert cell.certified and cell.lyapunov_p is not None
    loop = axis_loop(exp, controller, None, inner, fuzzy, stiffness * 1e3, latency, SIGMA_MIN)
    loop = replace(loop, sigma_min=cell.contact_sector[0])
    box = None
    if fuzzy is not None:
        g = effective_gains(controller, None)[0]
        box = (fuzzy.rho, g["ki"], g["kp"])
    return cell, loop, box


CASES = [("fuzzy-pi", 10.0, (1, 1)), ("pi", 10.0, (1, 1)), ("pi", 5.0, (0, 0))]


def _own_conditions(loop, box, rest_force=10.0):
    """The model's validity conditions written here from the closed-loop matrices, as rows
    ``h`` with ``h' x <= 1`` (one-sided; the level set is symmetric, so both signs are kept)."""
    s = loop.sensor_delay
    damp = loop.damping_n_s_per_m / (loop.stiffness_n_per_m * loop.period_s)
    rows = []
    for sigma, phi, a, g, de, q, lag, *_ in vertices(loop):
        nxt = closed_loop_matrix(loop, sigma, phi, a, g, de, q, lag)
        now = np.eye(loop.order)
        # contact in its sector: spring-damper deviation >= -rest force / sigma_min
        spring = (1.0 - lag + damp) * nxt[0] + (lag - damp) * now[0]
        rows.append(-spring * loop.sigma_min / rest_force)
        if box is not None:
            rho, ki, kp = box
            rows += [ki * nxt[2 + s] / rho, kp * (nxt[2 + s] - now[2 + s]) / rho]
    return [r for h in rows for r in (h, -h)]


@pytest.mark.parametrize(("controller", "stiffness", "latency"), CASES)
def test_region_n_is_the_largest_level_set_inside_every_condition(controller, stiffness, latency):
    from scipy.optimize import minimize

    cell, loop, box = _cell(controller, stiffness, latency)
    p = cell.lyapunov_p
    n = p.shape[0]
    ones = np.ones(n)
    gamma = (cell.region_n * ones) @ p @ (cell.region_n * ones)
    assert level_set(p, validity_slabs(loop, 10.0, box)).gamma == pytest.approx(gamma)
    # an independent optimiser: the largest value of each condition over x'Px <= gamma is at
    # most 1, and 1 for the one that limits the level set (so the set is the largest)
    best = []
    for h in _own_conditions(loop, box):
        res = minimize(
            lambda x, h=h: -(h @ x),
            x0=np.zeros(n),
            jac=lambda x, h=h: -h,
            constraints=[
                {"type": "ineq", "fun": lambda x: gamma - x @ p @ x, "jac": lambda x: -2 * p @ x}
            ],
            method="SLSQP",
            options={"ftol": 1e-15, "maxiter": 1000},
        )
        best.append(-res.fun)
    assert max(best) == pytest.approx(1.0, rel=1e-5)
    # samples of the level set's boundary: none violates a condition
    rng = np.random.default_rng(0)
    w, v = np.linalg.eigh(p)
    z = rng.standard_normal((20000, n))
    z /= np.linalg.norm(z, axis=1)[:, None]
    xs = math.sqrt(gamma) * z @ np.diag(1.0 / np.sqrt(w)) @ v.T
    assert np.allclose(np.einsum("ij,jk,ik->i", xs, p, xs), gamma)
    worst = max(float(np.max(xs @ h)) for h in _own_conditions(loop, box))
    assert 0.3 < worst <= 1.0 + 1e-9


@pytest.mark.parametrize(("controller", "stiffness", "latency"), CASES)
def test_switched_trajectories_from_the_region_stay_where_the_model_holds(
    controller, stiffness, latency
):
    # from the rest state region_n off the rest point, switch between the vertices at random;
    # the contact deviation and the fuzzy-PI's inputs are computed here from the state, not by
    # the rows the region was computed from
    cell, loop, box = _cell(controller, stiffness, latency)
    p = cell.lyapunov_p
    s = loop.sensor_delay
    damp = loop.damping_n_s_per_m / (loop.stiffness_n_per_m * loop.period_s)
    verts = vertices(loop)
    rng = np.random.default_rng(1)
    for scale in (1.0, -1.0):
        x = scale * cell.region_n * np.ones(loop.order)
        v = x @ p @ x
        worst_contact, worst_e, worst_de = 0.0, 0.0, 0.0
        for _ in range(1500):
            sigma, phi, a, g, de, q, lag, *_ = verts[rng.integers(len(verts))]
            nxt = closed_loop_matrix(loop, sigma, phi, a, g, de, q, lag) @ x
            spring = (1.0 - lag + damp) * nxt[0] + (lag - damp) * x[0]
            worst_contact = max(worst_contact, -spring * loop.sigma_min / 10.0)
            y_now, y_next = x[2 + s], nxt[2 + s]
            if box is not None:
                rho, ki, kp = box
                worst_e = max(worst_e, abs(ki * y_next) / rho)
                worst_de = max(worst_de, abs(kp * (y_next - y_now)) / rho)
            v_next = nxt @ p @ nxt
            assert v_next <= v * (1.0 + 1e-12)
            x, v = nxt, v_next
        assert worst_contact <= 1.0 + 1e-9
        assert worst_e <= 1.0 + 1e-9 and worst_de <= 1.0 + 1e-9


def test_cli_reports_region_n_for_every_certified_cell(capsys, tmp_path):
    argv = ["stability", "regulate", "--controller", "fuzzy-pi", "--plant", "arm6"]
    argv += ["--stiffness", "10,1000", "--latency", "1:1"]
    assert main([*argv, "--json"]) == 0
    cells = json.loads(capsys.readouterr().out)["cells"]
    for c in cells:
        if c["certified"]:
            assert c["region_n"] > 0.0 and c["region_limited_by"]
        else:
            assert c["region_n"] is None
    assert any(c["certified"] for c in cells)
    assert main([*argv, "--png", str(tmp_path / "r.png")]) == 0
    assert "region_n" in capsys.readouterr().out
