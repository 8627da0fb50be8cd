"""A quadrature with a proven error bound for an analytic aggregated output set.

Class: Gaussian output terms, product implication, probabilistic-sum aggregation, centroid.
The aggregated set ``f(y) = 1 - prod_p (1 - L_p g_p(y))`` (``L_p`` in [0, 1] the piece levels,
``g_p`` the pieces' Gaussians) is then an entire function of ``y`` with no breakpoint that
depends on the input, so a composite Gauss-Legendre rule over ``S`` equal cells of the output
range with ``n`` nodes each, fixed at generation time, integrates area and moment; the
generated code evaluates ``f`` at the nodes from a table of ``g_p`` (the terms do not depend on
the input) and folds the probabilistic sum scaled by the largest level ``s``
(``F <- F + X - s F X`` with ``X = (L_p / s) g_p``, which is ``f / s`` exactly in real
arithmetic): the centroid does not change, and levels far below float's smallest normal
(every firing strength tiny) neither underflow nor vanish against 1.

Proof of the bound (printed in the generated header):

* Gauss-Legendre with ``n`` nodes on [-1, 1] for ``F`` analytic in the Bernstein ellipse
  ``E_rho`` and ``|F| <= M`` there errs by at most ``64/15 M rho^(-2n) / (rho^2 - 1)``
  (Trefethen, "Is Gauss quadrature better than Clenshaw-Curtis?", SIAM Review 50 (2008),
  Thm. 4.5). A cell of half-width ``h`` maps ``E_rho`` to points ``z`` with
  ``|Im z| <= eta = h (rho - 1/rho) / 2``, and ``|exp(-(z - m)^2 / 2 s^2)| <=
  exp(eta^2 / 2 s^2) <= E`` (``s`` the smallest sigma).
* Expanding the product, ``|f(z)| <= prod (1 + L_p |g_p|) - 1 <= exp(Lambda E) - 1 <=
  Lambda (exp(P E) - 1) / P`` with ``Lambda = sum L_p <= P`` (``(e^{xE} - 1)/x`` grows in x).
* The area is at least ``max_p L_p a_p >= Lambda a_min / P`` (the sum is at least each term;
  ``a_p`` the integral of ``g_p`` over the range, in closed form with erf). Summing the cells'
  errors (``S h = W / 2``), the relative error of the area is at most
  ``delta = W/2 * 64/15 rho^(-2n) / (rho^2 - 1) * (exp(P E) - 1) / a_min``, whatever the
  levels, tiny ones included; the moment's error is at most ``Y' delta A`` with
  ``Y' = Y + h (rho + 1/rho) / 2`` and ``Y`` the largest |range end|.
* The centroid ``c = Mo / A`` then errs by at most ``delta (Y + Y') / (1 - delta)``.

``rho`` is any value > 1; the bound is minimised over a fixed grid of values, and ``S``, ``n``
are the first pair (fewest nodes) that meet :data:`TARGET` of the output range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import OutputPieces

#: The bound the quadrature meets, as a fraction of the output range (below the issue's 1e-9
#: for double, and below the double rounding bound's order so --verify's allowance holds).
TARGET = 1e-12
#: Candidate (cells, nodes per cell), fewest nodes first.
CHOICES = tuple(sorted(((s, n) for s in (2, 4, 8, 16, 32) for n in range(6, 21)),
                       key=lambda c: (c[0] * c[1], c[0])))  # fmt: skip
RHOS = np.linspace(1.01, 30.0, 3000)


FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Quadrature:
    """The fixed nodes and weights over the output range, and the proven centroid bound."""

    nodes: FloatArray
    weights: FloatArray
    cells: int
    per_cell: int
    bound: float  # |centroid error| in output units


def centroid_bound(
    low: float, high: float, means: list[float], sigmas: list[float], cells: int, n: int
) -> float:
    """The module docstring's bound on the centroid error (output units), inf if unproven."""
    width = high - low
    h = width / (2 * cells)
    p = len(means)
    a_min = min(
        s * math.sqrt(0.5 * math.pi)
        * (math.erf((high - m) / (s * math.sqrt(2))) - math.erf((low - m) / (s * math.sqrt(2))))
        for m, s in zip(means, sigmas, strict=True)
    )  # fmt: skip
    y = max(abs(low), abs(high))
    best = math.inf
    for rho in RHOS:
        eta = h * (rho - 1.0 / rho) / 2.0
        x = eta * eta / (2.0 * min(sigmas) ** 2)
        if p * math.exp(x) > 600.0:
            break  # exp would overflow: larger rho only loosens the growth term
        growth = math.expm1(p * math.exp(x))
        delta = width / 2 * 64 / 15 * rho ** (-2 * n) / (rho * rho - 1) * growth / a_min
        if delta < 1.0:
            y2 = y + h * (rho + 1.0 / rho) / 2.0
            best = min(best, delta * (y + y2) / (1.0 - delta))
    return best


def quadrature(low: float, high: float, means: list[float], sigmas: list[float]) -> Quadrature:
    """The fewest-node composite Gauss-Legendre rule whose proven bound meets :data:`TARGET`."""
    for cells, n in CHOICES:
        bound = centroid_bound(low, high, means, sigmas, cells, n)
        if bound <= TARGET * (high - low):
            t, w = np.polynomial.legendre.leggauss(n)
            h = (high - low) / (2 * cells)
            centres = low + h * (2 * np.arange(cells) + 1)
            nodes = (centres[:, None] + h * t[None, :]).ravel()
            weights = np.tile(h * w, cells)
            return Quadrature(nodes, weights, cells, n, bound)
    raise ValueError("no composite Gauss-Legendre rule of the candidates meets the target")


def applies(rb: RuleBase, out: Variable, pieces: OutputPieces) -> Quadrature | None:
    """The proven quadrature of an output of this module's class (Gaussian terms, product
    implication, probabilistic sum, centroid), else None (also when no candidate rule meets
    the bound: narrow terms on a wide range)."""
    ops = rb.operators
    if not (
        rb.defuzzifier == "centroid"
        and ops.implication == "product"
        and ops.aggregation == "probabilistic_sum"
        and out.terms
        and all(t.shape == "gaussian" for t in out.terms)
        and not pieces.empty
    ):
        return None
    terms = [out.terms[int(t)] for t in pieces.piece_term]
    try:
        return quadrature(
            out.low,
            out.high,
            [float(t.params[0]) for t in terms],
            [float(t.params[1]) for t in terms],
        )
    except ValueError:
        return None


def terms_at_nodes(rule: Quadrature, out: Variable, pieces: OutputPieces) -> FloatArray:
    """Each piece's Gaussian at every node, (P, N)."""
    m = np.array([out.terms[int(t)].params[0] for t in pieces.piece_term], dtype=float)
    s = np.array([out.terms[int(t)].params[1] for t in pieces.piece_term], dtype=float)
    table: FloatArray = np.exp(-0.5 * ((rule.nodes[None, :] - m[:, None]) / s[:, None]) ** 2)
    return table


__all__ = [
    "CHOICES",
    "TARGET",
    "Quadrature",
    "applies",
    "centroid_bound",
    "quadrature",
    "terms_at_nodes",
]
