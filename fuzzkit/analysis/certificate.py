"""The stability certificate: a quadratic Lyapunov function common to every vertex of the loop's
parameter box, found by an LMI (the Clarabel solver) and verified in numpy.

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
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: The smallest verified decay of V per period that counts as a certificate.
MIN_MARGIN = 1e-6
#: Lower bound on lambda_min(P) / lambda_max(P) checked in numpy (P must be positive definite,
#: not merely semidefinite to rounding).
MIN_CONDITION = 1e-10
#: The growing search (:func:`certify`): rounds on a subset of the vertices before one on all,
#: and how many of the worst vertices join the subset per round.
ROUNDS = 3
ADD_PER_ROUND = 2
#: Clarabel's tolerances: looser than its defaults (1e-8), because the answer is verified
#: independently and a margin must be >= MIN_MARGIN anyway; it saves iterations.
SOLVER_SETTINGS = {"tol_gap_abs": 1e-7, "tol_gap_rel": 1e-7, "tol_feas": 1e-7}


@dataclass(frozen=True, slots=True)
class Certificate:
    """The outcome for one set of vertex matrices.

    ``certified``: the numpy check passed. ``margin``: the verified decay per period (negative
    or NaN when no certificate was found). ``solver_status``: how it was decided (Clarabel's
    status, the refusal, or the reuse). ``p``: the Lyapunov matrix (None when none was found).
    """

    certified: bool
    margin: float
    solver_status: str
    p: FloatArray | None = None


def verify(p: FloatArray, matrices: list[FloatArray]) -> float:
    """The verified margin of ``V = x' P x`` for ``matrices`` (NaN if ``P`` is not definite)."""
    return float(np.min(vertex_margins(p, matrices)))


def vertex_margins(p: FloatArray, matrices: list[FloatArray]) -> FloatArray:
    """``lambda_min(P - A_i' P A_i) / lambda_max(P)`` for each matrix (all NaN if ``P`` is not
    definite)."""
    p = 0.5 * (p + p.T)
    eig_p = np.linalg.eigvalsh(p)
    if not (np.all(np.isfinite(eig_p)) and eig_p[0] > MIN_CONDITION * eig_p[-1] > 0.0):
        return np.full(len(matrices), math.nan)
    out = np.empty(len(matrices))
    for i, a in enumerate(matrices):
        q = p - a.T @ p @ a
        out[i] = float(np.linalg.eigvalsh(0.5 * (q + q.T))[0])
    return out / float(eig_p[-1])


def certify(
    matrices: list[FloatArray],
    core: list[FloatArray] | None = None,
    reuse: Sequence[FloatArray | None] = (),
) -> Certificate:
    """Search for a common quadratic Lyapunov function of ``matrices`` and verify it.

    A vertex with a spectral radius of 1 or more has no decreasing quadratic function at all:
    such a set is refused without calling the solver. ``reuse``: candidate ``P`` matrices (a
    neighbouring cell's, say), each verified on every matrix; the first that passes is the
    certificate, without a solve. Then a product of two vertices with a spectral radius of 1
    or more also refuses the set (:func:`pair_radius`). ``core``: a smaller set to search on
    first (the solve is cheaper); its ``P`` is verified on every matrix, the worst
    ``ADD_PER_ROUND`` vertices it fails on join the set and the search is repeated, up to
    ``ROUNDS`` times, before one search on all of them. Whichever way, a certificate is the
    numpy check on all of ``matrices``.
    """
    radius = max(float(np.max(np.abs(np.linalg.eigvals(a)))) for a in matrices)
    if radius >= 1.0:
        return Certificate(False, 1.0 - radius, "refused: a vertex has spectral radius >= 1")
    for p in reuse:
        if p is not None and p.shape == matrices[0].shape:
            margin = verify(p, matrices)
            if math.isfinite(margin) and margin >= MIN_MARGIN:
                return Certificate(True, margin, "reused (verified)", p)
    radius = pair_radius(matrices)
    if radius >= 1.0:
        return Certificate(
            False, 1.0 - radius, "refused: a product of two vertices has spectral radius >= 1"
        )
    working = list(core or [])
    for _ in range(ROUNDS if 0 < len(working) < len(matrices) else 0):
        first = _search(working)
        if first.p is None:
            break
        margins = vertex_margins(first.p, matrices)
        if np.all(np.isfinite(margins)) and margins.min() >= MIN_MARGIN:
            note = f" ({len(working)} of {len(matrices)} vertices searched)"
            return Certificate(True, float(margins.min()), first.solver_status + note, first.p)
        if not np.all(np.isfinite(margins)):
            break
        worst = [int(i) for i in np.argsort(margins)[:ADD_PER_ROUND] if margins[i] < MIN_MARGIN]
        working += [matrices[i] for i in worst]
    found = _search(matrices)
    if found.p is None:
        return found
    margin = verify(found.p, matrices)
    ok = bool(math.isfinite(margin) and margin >= MIN_MARGIN)
    return Certificate(ok, margin, found.solver_status, found.p)


def pair_radius(matrices: list[FloatArray]) -> float:
    """The largest spectral radius of a product ``A_i A_j`` of two different matrices.

    A necessary condition: if ``A_i' P A_i < P`` for every ``i``, then
    ``(A_i A_j)' P (A_i A_j) < A_j' P A_j < P``, so every product is stable too. A set with a
    product of radius >= 1 has no common quadratic Lyapunov function, and the solver need not
    be asked.
    """
    if len(matrices) < 2:
        return 0.0
    stack = np.asarray(matrices)
    i, j = np.triu_indices(len(matrices), 1)
    return float(np.max(np.abs(np.linalg.eigvals(stack[i] @ stack[j]))))


def _search(matrices: list[FloatArray]) -> Certificate:
    """Solve the SDP on ``matrices`` with Clarabel; the certificate carries ``P`` unverified.

    The program is handed to Clarabel directly (no modelling layer to compile per cell):
    unknowns ``x = (p_ij for i <= j, t)``, each constraint ``M(x) = M0 + sum_k x_k M_k >= 0``
    as ``svec(M0) - A x in`` Clarabel's triangle cone (``svec``: the upper triangle column
    by column, off-diagonal entries times sqrt(2)).
    """
    import clarabel
    import scipy.sparse as sp

    n = matrices[0].shape[0]
    cols, rows = np.tril_indices(n)  # (rows[k], cols[k]): the upper triangle, column by column
    scale = np.where(rows == cols, 1.0, math.sqrt(2.0))
    basis = np.zeros((rows.size, n, n))
    basis[np.arange(rows.size), rows, cols] = 1.0
    basis[np.arange(rows.size), cols, rows] = 1.0
    stack = np.asarray(matrices)
    # column k of a block: -svec(M_k); P <= I, then P - A' P A - t I >= 0 for every A
    blocks = [np.hstack([basis[:, rows, cols].T * scale[:, None], np.zeros((rows.size, 1))])]
    lyap = basis[None] - np.swapaxes(stack, 1, 2)[:, None] @ basis[None] @ stack[:, None]
    eye = np.where(rows == cols, 1.0, 0.0)
    for m in lyap:
        blocks.append(np.hstack([-(m[:, rows, cols].T * scale[:, None]), eye[:, None]]))
    a_mat = sp.csc_matrix(np.vstack(blocks))
    b = np.concatenate([eye, np.zeros(rows.size * len(matrices))])
    q = np.zeros(rows.size + 1)
    q[-1] = -1.0  # maximise t
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    for name, value in SOLVER_SETTINGS.items():
        setattr(settings, name, value)
    cones = [clarabel.PSDTriangleConeT(n)] * (len(matrices) + 1)
    # a numerical failure is a status (with whatever x it reached), not an exception
    solution = clarabel.DefaultSolver(
        sp.csc_matrix((q.size, q.size)), q, a_mat, b, cones, settings
    ).solve()
    status = str(solution.status)
    x = np.asarray(solution.x, dtype=np.float64)
    if x.size != q.size or not np.all(np.isfinite(x)):
        return Certificate(False, math.nan, status)
    p = np.zeros((n, n))
    p[rows, cols] = x[:-1]
    p[cols, rows] = x[:-1]
    return Certificate(False, math.nan, status, p)
