"""Sound enclosures of an interval type-2 rule base's exact outputs over input rectangles.

The exact IT2 output is ``(y_l + y_r) / 2``, where ``[y_l, y_r]`` is the Karnik-Mendel interval:
the least and the greatest centroid of the type-1 sets ``f`` embedded in the footprint,
``L(x) <= f <= U(x)`` (continuous, :mod:`fuzzkit.fuzzy.type_reduction`). So ``y_l`` can only
fall and ``y_r`` only rise when the footprint grows. Over a rectangle of inputs:

1. **Piece levels.** Each input term's upper membership ``mu_u`` and lower membership
   ``mu_l = min(h mu_lower, mu_u)`` over the rectangle's side: a trapezoid is unimodal, so its
   least value is at an end and its greatest is 1 where the side meets the core, else at an
   end. The rule's AND (``min`` or ``product``), its weight and the max over the rules of a
   piece are monotone, so each piece's upper level lies in ``[u_min, u_max]`` and its lower
   level in ``[l_min, l_max]``.
2. **Wide footprint** ``(u_max, l_min)``: at every point of the rectangle ``L(x) >= L(l_min)``
   and ``U(x) <= U(u_max)`` (the sets are monotone in the levels; the lower output sets lie
   under the upper ones and each lower level under its upper one, so the kernel's clip of
   ``L`` to ``U`` does not bind), so its interval ``[y_l^w, y_r^w]`` holds every ``[y_l(x),
   y_r(x)]``: ``y_l(x) >= y_l^w`` and ``y_r(x) <= y_r^w``.
3. **Narrow footprint** ``(u_min, l_max)``, where every piece has ``l_max <= u_min``: then
   ``L(l_max) <= U(u_min)`` is a footprint inside every ``[L(x), U(x)]``, so ``y_l(x) <= y_l^n``
   and ``y_r(x) >= y_r^n``. Where some piece has ``l_max > u_min`` there is no such footprint
   and the bounds fall back to ``y_l(x) <= y_r(x) <= y_r^w``, ``y_r(x) >= y_l^w``.

Both footprints' intervals come from the engine's compiled type reduction
(:func:`fuzzkit.fuzzy.type2_kernel.continuous_intervals`); every bound is widened by
:data:`ROUNDING` of the output range, the rounding of that reduction. A rectangle where no rule
surely fires (every ``u_min`` 0) can give the output's ``default``: its enclosure is refused
there (``None``) unless the default is a number, which then widens it. Only values are
enclosed: the certificate also needs slopes (``dy_l/dL_t = int (y - y_l) df*/dL_t / D`` with
``f*`` = ``U`` left of ``y_l``, ``L`` right of it: the type-1 centroid's form), which this
module does not give yet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.type2_inference import _Type2Mamdani
from fuzzkit.fuzzy.type2_kernel import _FIRE_HEADER, _OUT_HEADER, continuous_intervals

FloatArray = npt.NDArray[np.float64]

#: Widening of every bound, as a share of the output range (the type reduction's rounding,
#: about 1e-15 of it, with a wide margin).
ROUNDING = 1e-12


@dataclass(frozen=True)
class Type2Box:
    """Enclosures over one rectangle: ``y_l``, ``y_r`` and the output, each ``(low, high)``."""

    y_l: tuple[float, float]
    y_r: tuple[float, float]
    output: tuple[float, float]
    narrow: bool  # the narrow footprint applied (tighter inner bounds)


def _trapezoid_range(form: FloatArray, x0: float, x1: float) -> tuple[float, float]:
    """Least and greatest of a trapezoid-form term (``membership.trapezoid_form``) on
    ``[x0, x1]``."""

    def mu(x: float) -> float:
        v = min(1.0 + (x - form[0]) * form[2], 1.0 + (form[1] - x) * form[3])
        return float(min(max(v, 0.0), 1.0))

    a, b = mu(x0), mu(x1)
    top = 1.0 if x0 <= form[1] and x1 >= form[0] else max(a, b)
    return min(a, b), top


class Type2Enclosure:
    """Value enclosures of a continuous-KM IT2 rule base's one Mamdani output."""

    def __init__(self, rb: RuleBase) -> None:
        engine = Engine(rb)._type2
        out = None if engine is None or len(engine.outputs) != 1 else engine.outputs[0]
        if engine is None or engine.compiled is None or not isinstance(out, _Type2Mamdani):
            raise ValueError(f"rule base {rb.name!r}: no compiled exact IT2 layout to enclose")
        self.firing = engine.compiled
        self.layout = out.layout
        self.low, self.high = out.low, out.high
        self.default = out.default

    def _levels(self, box: FloatArray) -> FloatArray:
        """(4, pieces): ``u_min, u_max, l_min, l_max`` over ``box`` (inputs, 2)."""
        ff, fi = self.firing.floats, self.firing.ints
        n_in, n_t, n_rules, n_leaves = (int(v) for v in fi[:4])
        rl = n_rules * n_leaves
        leaf_in = fi[_FIRE_HEADER : _FIRE_HEADER + rl].reshape(n_rules, n_leaves)
        leaf_term = fi[_FIRE_HEADER + rl : _FIRE_HEADER + 2 * rl].reshape(n_rules, n_leaves)
        tf = n_in * n_t * 4
        forms = ff[2 * n_in : 2 * n_in + 2 * tf].reshape(2, n_in, n_t, 4)
        h0 = 2 * n_in + 2 * tf
        heights = ff[h0 : h0 + n_in * n_t].reshape(n_in, n_t)
        weights = ff[h0 + n_in * n_t : h0 + n_in * n_t + n_rules]
        lo = np.clip(box[:, 0], ff[:n_in], ff[n_in : 2 * n_in])
        hi = np.clip(box[:, 1], ff[:n_in], ff[n_in : 2 * n_in])
        product = bool(fi[4])
        rules = np.empty((4, n_rules))
        for r in range(n_rules):
            acc = np.ones(4)
            for v, t in zip(leaf_in[r], leaf_term[r], strict=True):
                if v < 0:
                    break
                u0, u1 = _trapezoid_range(forms[0, v, t], lo[v], hi[v])
                w0, w1 = _trapezoid_range(forms[1, v, t], lo[v], hi[v])
                mu = np.array([u0, u1, min(heights[v, t] * w0, u0), min(heights[v, t] * w1, u1)])
                acc = acc * mu if product else np.minimum(acc, mu)
            rules[:, r] = acc * weights[r]
        li = self.layout.ints
        n_pieces, n_inst = int(li[2]), int(li[3])
        inst_rule = li[_OUT_HEADER : _OUT_HEADER + n_inst]
        inst_piece = li[_OUT_HEADER + n_inst : _OUT_HEADER + 2 * n_inst]
        levels = np.zeros((4, n_pieces))
        for r, p in zip(inst_rule, inst_piece, strict=True):
            levels[:, p] = np.maximum(levels[:, p], rules[:, r])
        return levels

    def enclose(self, box: FloatArray) -> Type2Box | None:
        """The enclosures over ``box`` ((inputs, 2): each input's ``[low, high]``), or None
        where the output may be an undefined default (no rule surely fires, default NaN)."""
        u_min, u_max, l_min, l_max = self._levels(np.asarray(box, dtype=np.float64))
        may_default = not np.any(u_min > 0.0)
        if not np.any(u_max > 0.0):  # nothing can fire: the default everywhere
            return None if np.isnan(self.default) else _point(self.default)
        if may_default and np.isnan(self.default):
            return None
        narrow = bool(np.all(l_max <= u_min)) and not may_default
        rows = continuous_intervals(
            np.stack([u_max, u_min]), np.stack([l_min, np.minimum(l_max, u_min)]), self.layout
        )
        pad = ROUNDING * (self.high - self.low)
        wl, wr = float(rows[0, 0]), float(rows[0, 1])
        if narrow:
            nl, nr = float(rows[1, 0]), float(rows[1, 1])
        else:
            nl, nr = wr, wl
        y_l = (wl - pad, nl + pad)
        y_r = (nr - pad, wr + pad)
        lo_out, hi_out = 0.5 * (y_l[0] + y_r[0]), 0.5 * (y_l[1] + y_r[1])
        if may_default:
            lo_out, hi_out = min(lo_out, self.default), max(hi_out, self.default)
        return Type2Box(y_l, y_r, (lo_out, hi_out), narrow)


def _point(v: float) -> Type2Box:
    return Type2Box((v, v), (v, v), (v, v), False)


__all__ = ["ROUNDING", "Type2Box", "Type2Enclosure"]
