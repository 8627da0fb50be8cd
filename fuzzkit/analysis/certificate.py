"""The stability certificate: a quadratic Lyapunov function common to every vertex of the loop's
parameter box, found by an LMI (cvxpy with the Clarabel solver) and verified in numpy.

For vertex matrices ``A_i``, the semidefinite program

    maximise t  subject to  P <= I,  P - A_i' P A_i >= t I  for every i

(linear in ``P`` and ``t`` for the known ``A_i``) looks for ``V(x) = x' P x``
decreasing along every trajectory of the polytopic system. The solver's answer is never taken
on trust: the returned ``P`` is symmetrised and checked with numpy's symmetric eigenvalues,

    margin = min_i lambda_min(P - A_i' P A_i) / lambda_max(P),    lambda_min(P) > 0,

and the cell is certified only when ``margin >= MIN_MARGIN``. ``margin`` is the guaranteed decay
of ``V`` per period (``V[k+1] <= (1 - margin) V[k]``, also for any convex combination of the
``A_i``, since ``x' A' P A x`` is convex in ``A``); the threshold is far above the eigenvalue
routine's rounding (about ``n * eps * ||P|| * ||A||^2``: below 1e-9 with ``||P|| <= 1`` and
``||A||`` up to a few hundred), so a solver tolerance cannot turn a failed certificate into a
pass.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: The smallest verified decay of V per period that counts as a certificate.
MIN_MARGIN = 1e-6
#: Lower bound on lambda_min(P) / lambda_max(P) checked in numpy (P must be positive definite,
#: not merely semidefinite to rounding).
MIN_CONDITION = 1e-10
#: Clarabel's tolerances: looser than its defaults (1e-8), because the answer is verified
#: independently and a margin must be >= MIN_MARGIN anyway; it saves iterations.
SOLVER_SETTINGS = {"tol_gap_abs": 1e-7, "tol_gap_rel": 1e-7, "tol_feas": 1e-7}


@dataclass(frozen=True, slots=True)
class Certificate:
    """The outcome for one set of vertex matrices.

    ``certified``: the numpy check passed. ``margin``: the verified decay per period (negative
    or NaN when no certificate was found). ``solver_status``: cvxpy's status. ``p``: the
    Lyapunov matrix (None when the solver returned none).
    """

    certified: bool
    margin: float
    solver_status: str
    p: FloatArray | None = None


def verify(p: FloatArray, matrices: list[FloatArray]) -> float:
    """The verified margin of ``V = x' P x`` for ``matrices`` (NaN if ``P`` is not definite)."""
    p = 0.5 * (p + p.T)
    eig_p = np.linalg.eigvalsh(p)
    if not (np.all(np.isfinite(eig_p)) and eig_p[0] > MIN_CONDITION * eig_p[-1] > 0.0):
        return math.nan
    worst = math.inf
    for a in matrices:
        q = p - a.T @ p @ a
        worst = min(worst, float(np.linalg.eigvalsh(0.5 * (q + q.T))[0]))
    return worst / float(eig_p[-1])


def certify(matrices: list[FloatArray], core: list[FloatArray] | None = None) -> Certificate:
    """Search for a common quadratic Lyapunov function of ``matrices`` and verify it.

    A vertex with a spectral radius of 1 or more has no decreasing quadratic function at all:
    such a set is refused without calling the solver. ``core``: a smaller set to search on
    first (the solve is cheaper); its ``P`` is then verified on every matrix, and only if that
    fails is the search repeated on all of them. Either way the verdict is the numpy check on
    all of ``matrices``.
    """
    radius = max(float(np.max(np.abs(np.linalg.eigvals(a)))) for a in matrices)
    if radius >= 1.0:
        return Certificate(False, 1.0 - radius, "refused: a vertex has spectral radius >= 1")
    if core is not None and len(core) < len(matrices):
        first = _search(core)
        if first.p is not None:
            margin = verify(first.p, matrices)
            if math.isfinite(margin) and margin >= MIN_MARGIN:
                return Certificate(True, margin, first.solver_status + " (core)", first.p)
    found = _search(matrices)
    if found.p is None:
        return found
    margin = verify(found.p, matrices)
    ok = bool(math.isfinite(margin) and margin >= MIN_MARGIN)
    return Certificate(ok, margin, found.solver_status, found.p)


def _search(matrices: list[FloatArray]) -> Certificate:
    """Solve the SDP on ``matrices``; the returned certificate carries ``P`` unverified."""
    import cvxpy

    cp: Any = cvxpy  # untyped library
    n = matrices[0].shape[0]
    eye = np.eye(n)
    p = cp.Variable((n, n), symmetric=True)
    t = cp.Variable()
    cons = [p << eye] + [p - a.T @ p @ a - t * eye >> 0 for a in matrices]
    problem = cp.Problem(cp.Maximize(t), cons)
    try:
        with warnings.catch_warnings():
            # "solution may be inaccurate": the numpy check decides, not the status
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL, **SOLVER_SETTINGS)
    except cp.error.SolverError as exc:
        return Certificate(False, math.nan, f"solver error: {exc}")
    status = str(problem.status)
    if p.value is None:
        return Certificate(False, math.nan, status)
    return Certificate(False, math.nan, status, np.array(p.value, dtype=np.float64))
