"""The loop model and the certificate (fuzzkit.analysis.loop_model, .certificate)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fuzzkit.analysis.certificate import MIN_MARGIN, certify, verify
from fuzzkit.analysis.loop_model import AxisLoop, closed_loop_matrix, noise_std, vertex_matrices


def _loop(**kw):
    base = dict(
        period_s=0.004,
        stiffness_n_per_m=1e4,
        damping_n_s_per_m=50.0,
        sensor_delay=1,
        command_delay=1,
        filter_cutoff_hz=60.0,
        kp=4e-5,
        ki=1e-5,
        phi=(0.5, 1.9),
        inner_a=(0.6, 0.62),
        inner_g=(0.95, 1.05),
        sigma_min=0.1,
    )
    base.update(kw)
    return AxisLoop(**base)


def test_verify_gives_the_closed_form_margin():
    # A = 0.5 I, P = I: P - A'PA = 0.75 I, lambda_max(P) = 1
    assert verify(np.eye(3), [0.5 * np.eye(3)]) == pytest.approx(0.75)
    # a P that is not positive definite certifies nothing
    assert math.isnan(verify(np.diag([1.0, -1.0]), [0.5 * np.eye(2)]))


def test_a_vertex_with_spectral_radius_above_one_is_refused_without_the_solver():
    cert = certify([0.5 * np.eye(2), 1.01 * np.eye(2)])
    assert not cert.certified
    assert cert.solver_status.startswith("refused")


def test_stable_vertices_without_a_common_lyapunov_function_are_refused():
    # each is nilpotent (spectral radius 0), but A1 A2 = diag(4, 0): switching between them
    # diverges, so no common quadratic function can exist and the certificate must say no
    a1 = np.array([[0.0, 2.0], [0.0, 0.0]])
    a2 = np.array([[0.0, 0.0], [2.0, 0.0]])
    cert = certify([a1, a2])
    assert not cert.certified
    assert not cert.margin >= MIN_MARGIN


def test_a_core_certificate_still_holds_on_every_matrix():
    rng = np.random.default_rng(1)
    mats = [0.5 * np.eye(3) + 0.05 * rng.standard_normal((3, 3)) for _ in range(6)]
    cert = certify(mats, core=mats[:2])
    assert cert.certified
    assert cert.p is not None
    assert verify(cert.p, mats) == pytest.approx(cert.margin)


def test_a_certified_set_is_verified_independently():
    rng = np.random.default_rng(0)
    mats = [0.6 * np.eye(4) + 0.05 * rng.standard_normal((4, 4)) for _ in range(5)]
    cert = certify(mats)
    assert cert.certified
    p = cert.p
    assert p is not None
    # the decrease along every vertex, recomputed here from the returned P
    for a in mats:
        for _ in range(20):
            x = rng.standard_normal(4)
            v, v_next = x @ p @ x, (a @ x) @ p @ (a @ x)
            assert v_next <= (1.0 - cert.margin) * v + 1e-12


@pytest.mark.parametrize("name", ["sigma", "phi", "a", "g", "phi_de", "q", "lag"])
def test_the_loop_matrix_is_affine_in_each_parameter(name):
    # what makes the vertices enough: along any one parameter A is affine, so every point of
    # the box is a convex combination of the vertices
    loop = _loop(phi_de=(0.7, 1.2))
    base = {"sigma": 0.4, "phi": 1.1, "a": 0.61, "g": 1.01, "phi_de": 0.9, "q": 0.2, "lag": 0.3}

    def at(value: float) -> np.ndarray:
        args = {**base, name: value}
        return closed_loop_matrix(loop, **args)

    lo, hi, t = 0.3, 0.9, 0.37
    assert np.allclose(at(t * hi + (1 - t) * lo), t * at(hi) + (1 - t) * at(lo), atol=1e-12)


def test_vertex_count_is_the_product_of_the_intervals():
    assert len(vertex_matrices(_loop())) == 16
    assert len(vertex_matrices(_loop(phi=(1.0, 1.0), inner_g=(1.0, 1.0)))) == 4
    assert len(vertex_matrices(_loop(inner_q=(0.1, 0.2), contact_lag=(0.2, 0.7)))) == 64
    # the core keeps the time-varying gains' and the contact lag's corners only
    assert len(vertex_matrices(_loop(contact_lag=(0.2, 0.7)), nominal_plant=True)) == 8


def test_the_substep_lag_of_the_planar_sensor_is_its_filter_weighted_mean():
    from fuzzkit.analysis.loop_model import substep_lag

    # one substep: the force at the period's start, one whole period before the sample
    assert substep_lag(1, 60.0, 0.004) == pytest.approx(1.0)
    # 4 substeps of 1 ms at 60 Hz: weights alpha (1 - alpha)^j, lags (j + 1) / 4
    alpha = 1.0 - math.exp(-2.0 * math.pi * 60.0 * 0.001)
    w = [alpha * (1.0 - alpha) ** j for j in range(4)]
    expected = sum(wj * (j + 1) / 4 for j, wj in enumerate(w)) / sum(w)
    assert substep_lag(4, 60.0, 0.004) == pytest.approx(expected)
    assert 0.45 < expected < 0.55


def test_the_default_pi_is_stable_at_100_n_per_mm_without_latency_and_not_at_1_plus_1():
    # the README's simulated finding: default gains are stable but ringing at 100 N/mm without
    # latency and trip from 100 N/mm with one period each way
    nominal = dict(phi=(1.0, 1.0), inner_a=(math.exp(-0.5),) * 2, inner_g=(1.0, 1.0))
    for lat, stable in (((0, 0), True), ((1, 1), False)):
        loop = _loop(stiffness_n_per_m=1e5, sensor_delay=lat[0], command_delay=lat[1], **nominal)
        a = closed_loop_matrix(loop, 1.0, 1.0, math.exp(-0.5), 1.0, None, 0.0, 0.0)
        assert bool(max(abs(np.linalg.eigvals(a))) < 1.0) is stable


def test_bad_model_parameters_are_all_reported():
    with pytest.raises(ValueError, match=r"period_s must be > 0.*sigma_min must be in"):
        _loop(period_s=0.0, sigma_min=0.0)


def test_noise_std_is_infinite_for_an_unstable_nominal_loop():
    assert noise_std(_loop(stiffness_n_per_m=1e6, phi=(1.0, 1.0)), 0.1) == math.inf


def test_a_reused_p_is_accepted_only_after_passing_on_every_vertex():
    # P = I passes on 0.5 I with the closed-form margin 1 - 0.25 = 0.75, without a solve
    cert = certify([0.5 * np.eye(2)], reuse=[np.eye(2)])
    assert cert.certified and cert.solver_status.startswith("reused")
    assert cert.margin == pytest.approx(0.75)
    # a new vertex on which I fails (I - A'A has the eigenvalue below 0), though a common P
    # exists (A is stable): the reused I is not accepted, the certificate is a solved one
    a = np.array([[0.5, 0.0], [5.0, 0.5]])
    assert np.linalg.eigvalsh(np.eye(2) - a.T @ a)[0] < 0.0
    cert = certify([0.5 * np.eye(2), a], reuse=[np.eye(2)])
    assert not cert.solver_status.startswith("reused")
    assert cert.certified and cert.p is not None
    assert not np.allclose(cert.p / cert.p[0, 0], np.eye(2))
    assert verify(cert.p, [0.5 * np.eye(2), a]) == pytest.approx(cert.margin)
    # and where no common P exists, a reused one does not make a certificate
    a1 = np.array([[0.0, 2.0], [0.0, 0.0]])
    assert not certify([a1, a1.T], reuse=[np.eye(2), np.diag([1.0, 1e-3])]).certified


def test_a_product_of_two_vertices_with_radius_one_or_more_refuses_without_the_solver():
    from fuzzkit.analysis.certificate import pair_radius

    a1 = np.array([[0.0, 2.0], [0.0, 0.0]])
    # A1 A2 = diag(4, 0)
    assert pair_radius([a1, a1.T]) == pytest.approx(4.0)
    cert = certify([a1, a1.T])
    assert cert.solver_status.startswith("refused: a product")
    assert cert.margin == pytest.approx(-3.0)


def test_the_direct_clarabel_program_has_the_optimum_of_the_same_program_in_cvxpy():
    # the SDP maximise t s.t. P <= I, P - A'PA >= t I, written independently with cvxpy
    import cvxpy as cp

    rng = np.random.default_rng(3)
    mats = [0.55 * np.eye(4) + 0.12 * rng.standard_normal((4, 4)) for _ in range(5)]
    p, t = cp.Variable((4, 4), symmetric=True), cp.Variable()
    cons = [p << np.eye(4)] + [p - a.T @ p @ a - t * np.eye(4) >> 0 for a in mats]
    cp.Problem(cp.Maximize(t), cons).solve(solver=cp.CLARABEL)
    cert = certify(mats)  # no core: one search on all
    assert cert.certified
    assert cert.margin == pytest.approx(float(t.value), rel=1e-4)


def test_the_growing_search_adds_the_vertices_the_core_p_fails_on():
    # on the core {0.5 I} the search finds P = I (t = 0.75), which fails on the second vertex:
    # that vertex joins the search, and the P of the second round holds on both
    a = np.array([[0.5, 0.0], [5.0, 0.5]])
    mats = [0.5 * np.eye(2), a]
    cert = certify(mats, core=[0.5 * np.eye(2)])
    assert cert.certified and cert.p is not None
    assert "(2 of 2 vertices searched)" in cert.solver_status
    assert verify(cert.p, mats) == pytest.approx(cert.margin)
    assert cert.margin >= MIN_MARGIN
