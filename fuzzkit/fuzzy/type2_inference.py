"""The exact interval type-2 engine (Mamdani and Sugeno outputs) over batches of points.

Continuous Mamdani outputs run as one compiled kernel per output
(:mod:`fuzzkit.fuzzy.type2_kernel`): from the input values when the firing is one the kernel
covers (piecewise-linear input terms, conjunctive antecedents), else from the piece levels of
the numpy firing below; discretised (``resolution:``) and Sugeno outputs run in numpy.

:class:`fuzzkit.fuzzy.inference.Engine` hands a rule base with a footprint to
:class:`Type2Engine`, so ``Engine(rb).evaluate(...)``, surfaces, tables and generated code work
on IT2 rule bases unchanged. Semantics (docs/type2.md):

* **Firing interval** of a rule: ``[AND of lower memberships, AND of upper memberships]``
  with the rule base's AND (OR likewise), times the rule weight. Lower memberships are
  ``scale * lower_shape(x)``. Negated propositions are refused by validation (NOT swaps the
  ends, which the type-1 firing code does not do).
* **Implication** clips (``min``) or scales (``product``) the upper consequent by the upper
  firing and the lower consequent (``scale * lower_shape``) by the lower firing; **aggregation**
  is ``max`` and gives the upper and lower output sets ``U`` and ``L``.
* **Type reduction** (:mod:`fuzzkit.fuzzy.type_reduction`): on the continuous output universe
  by default, exactly (the sets are piecewise linear; the engine cuts them at every vertex,
  edge crossing and clipping point, the same cut as the type-1 engine's closed form); with
  ``resolution: N`` on ``N`` evenly spaced samples of the output range (MATLAB, pyit2fls).
  ``karnik-mendel`` and ``ekm`` give ``(y_l + y_r) / 2``.
* **Sugeno** outputs: each rule's consequent value ``z`` with its firing interval, reduced by
  Karnik-Mendel over the sorted ``z`` (or Nie-Tan, Wu-Mendel).
* A NaN input gives NaN outputs; no rule firing gives the output's default (NaN if none).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Protocol, cast

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy import membership, type_reduction
from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import OutputPieces, PiecewiseLinearGeometry
from fuzzkit.fuzzy.sugeno import SugenoOutput
from fuzzkit.fuzzy.type2_kernel import (
    FiringLayout,
    OutputLayout,
    continuous_intervals,
    evaluate_points,
)
from fuzzkit.fuzzy.type2_model import Footprint, Type2RuleBase

FloatArray = npt.NDArray[np.float64]


class Fuzzifier(Protocol):
    """Memberships of one input in all its terms (the type-1 engine's fuzzifier)."""

    def __call__(self, x: FloatArray) -> FloatArray: ...

    def prepare(self, x: FloatArray) -> FloatArray: ...


def lower_variable(var: Variable, footprint: Footprint) -> tuple[Variable, FloatArray]:
    """``var`` with its lower shapes as terms, and the terms' heights (scales)."""
    shapes, scales = footprint.lower_terms(var)
    return replace(var, terms=shapes), np.array(scales, dtype=np.float64)


class _Type2Mamdani:
    """Upper and lower output sets of one Mamdani output and their type reduction."""

    def __init__(self, rb: RuleBase, out: Variable, footprint: Footprint) -> None:
        self.name = out.name
        self.low, self.high = out.low, out.high
        self.default = math.nan if out.default is None else float(out.default)
        self.method = footprint.type_reduction
        self.implication = rb.operators.implication
        self.pieces = OutputPieces(rb, out)
        low_var, self.heights = lower_variable(out, footprint)
        self.resolution = footprint.resolution
        if self.resolution is not None:
            self.grid = np.linspace(out.low, out.high, self.resolution)
            self.upper_mu = np.stack([membership.evaluate_term(t, self.grid) for t in out.terms])
            self.lower_mu = self.heights[:, None] * np.stack(
                [membership.evaluate_term(t, self.grid) for t in low_var.terms]
            )
            return
        self.layout = OutputLayout.of(
            self.pieces,
            PiecewiseLinearGeometry(rb, out, self.pieces),
            PiecewiseLinearGeometry(rb, low_var, self.pieces, heights=self.heights.tolist()),
            self.implication == "product",
        )

    @property
    def continuous(self) -> bool:
        """Exact (continuous) type reduction, with rules to reduce."""
        return self.resolution is None and not self.pieces.empty

    def reduced_points(self, x: FloatArray, firing: FiringLayout) -> FloatArray:
        """As :meth:`reduced`, from the input values (B, I) in one compiled pass."""
        return evaluate_points(x, firing, self.layout)

    def value(self, reduced: FloatArray) -> FloatArray:
        """The output from :meth:`reduced`'s columns (the default where nothing fires)."""
        value = self._continuous(reduced)
        return np.where(np.isnan(value), self.default, value)

    def reduced(self, firing_lo: FloatArray, firing_up: FloatArray) -> FloatArray:
        """Continuous mode: ``y_l, y_r, A_U, M_U, A_L, M_L, first, last`` per point (B, 8),
        from the compiled kernel (:mod:`fuzzkit.fuzzy.type2_kernel`)."""
        return continuous_intervals(
            self.pieces.levels(firing_up), self.pieces.levels(firing_lo), self.layout
        )

    def sampled(
        self, firing_lo: FloatArray, firing_up: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The upper and lower sets on the discretised universe (B, N), resolution mode."""
        lv_u = self.pieces.levels(firing_up)
        lv_l = self.pieces.levels(firing_lo)
        term = self.pieces.piece_term
        if self.upper_mu.shape[0] == 0 or lv_u.shape[1] == 0:
            z = np.zeros((firing_up.shape[0], self.grid.size))
            return z, z
        mu_u = self.upper_mu[term][None]
        mu_l = self.lower_mu[term][None]
        imp = np.minimum if self.implication == "min" else np.multiply
        up = imp(lv_u[:, :, None], mu_u).max(axis=1)
        lo = imp(lv_l[:, :, None], mu_l).max(axis=1)
        return up, np.minimum(lo, up)

    def __call__(self, firing_lo: FloatArray, firing_up: FloatArray) -> FloatArray:
        b = firing_up.shape[0]
        if self.pieces.empty:
            return np.full(b, self.default)
        if self.resolution is None:
            return self.value(self.reduced(firing_lo, firing_up))
        up, lo = self.sampled(firing_lo, firing_up)
        value = self._discrete(np.broadcast_to(self.grid, up.shape), up, lo)
        return np.where(np.isnan(value), self.default, value)

    def interval(
        self, firing_lo: FloatArray, firing_up: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The Karnik-Mendel centroid interval ``(y_l, y_r)`` (NaN where nothing fires)."""
        b = firing_up.shape[0]
        if self.pieces.empty:
            return np.full(b, np.nan), np.full(b, np.nan)
        if self.resolution is None:
            r = self.reduced(firing_lo, firing_up)
            return r[:, 0], r[:, 1]
        up, lo = self.sampled(firing_lo, firing_up)
        return type_reduction.discrete_interval(np.broadcast_to(self.grid, up.shape), lo, up)

    def _continuous(self, reduced: FloatArray) -> FloatArray:
        y_l, y_r, a_u, m_u, a_l, m_l, first, last = reduced.T
        if self.method == "nie-tan":
            return type_reduction.nie_tan(a_u, m_u, a_l, m_l)
        if self.method == "wu-mendel":
            return type_reduction.wu_mendel(
                (a_l, m_l, m_l - first * a_l, last * a_l - m_l),
                (a_u, m_u, m_u - first * a_u, last * a_u - m_u),
            )
        return cast(FloatArray, 0.5 * (y_l + y_r))

    def _discrete(self, y: FloatArray, up: FloatArray, lo: FloatArray) -> FloatArray:
        return reduce_points(self.method, y, lo, up)


def reduce_points(method: str, y: FloatArray, lower: FloatArray, upper: FloatArray) -> FloatArray:
    """Type-reduce weighted points: ``y`` (B, n) with weights in ``[lower, upper]`` (B, n)."""
    order = np.argsort(y, axis=1, kind="stable")
    y = np.take_along_axis(y, order, axis=1)
    lower = np.take_along_axis(lower, order, axis=1)
    upper = np.take_along_axis(upper, order, axis=1)
    a_u, a_l = upper.sum(axis=1), lower.sum(axis=1)
    m_u, m_l = (y * upper).sum(axis=1), (y * lower).sum(axis=1)
    if method == "nie-tan":
        return type_reduction.nie_tan(a_u, m_u, a_l, m_l)
    if method == "wu-mendel":
        pos = upper > 0.0
        big = np.finfo(np.float64).max
        first = np.where(pos, y, big).min(axis=1, keepdims=True)
        last = np.where(pos, y, -big).max(axis=1, keepdims=True)
        first = np.where(np.isfinite(first) & (first < big), first, 0.0)
        last = np.where(last > -big, last, 0.0)
        return type_reduction.wu_mendel(
            (a_l, m_l, (lower * (y - first)).sum(axis=1), (lower * (last - y)).sum(axis=1)),
            (a_u, m_u, (upper * (y - first)).sum(axis=1), (upper * (last - y)).sum(axis=1)),
        )
    y_l, y_r = type_reduction.discrete_interval(y, lower, upper)
    return 0.5 * (y_l + y_r)


class _Type2Sugeno:
    """One Sugeno output: rule consequent values with their firing intervals, type-reduced."""

    def __init__(self, rb: RuleBase, out: Variable, footprint: Footprint) -> None:
        self.name = out.name
        self.default = math.nan if out.default is None else float(out.default)
        self.method = footprint.type_reduction
        # the type-1 Sugeno output's consequent table: one column per rule consequent
        self.consequents = SugenoOutput(rb, out)
        self.rules = self.consequents.inst_rules
        self.empty = self.rules.size == 0

    def _points(
        self, firing_lo: FloatArray, firing_up: FloatArray, inputs: list[FloatArray]
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        b = firing_up.shape[0]
        table = self.consequents
        z = np.broadcast_to(table.constants, (b, self.rules.size))
        if table.linear:
            z = np.stack(inputs, axis=1) @ table.slopes + table.constants
        lo, up = firing_lo[:, self.rules], firing_up[:, self.rules]
        return z, np.minimum(lo, up), up

    def interval(
        self, firing_lo: FloatArray, firing_up: FloatArray, inputs: list[FloatArray]
    ) -> tuple[FloatArray, FloatArray]:
        """The Karnik-Mendel interval over the rules' consequent values."""
        if self.empty:
            nan = np.full(firing_up.shape[0], np.nan)
            return nan, nan
        z, lo, up = self._points(firing_lo, firing_up, inputs)
        order = np.argsort(z, axis=1, kind="stable")
        take = np.take_along_axis
        return type_reduction.discrete_interval(
            take(z, order, axis=1), take(lo, order, axis=1), take(up, order, axis=1)
        )

    def __call__(
        self, firing_lo: FloatArray, firing_up: FloatArray, inputs: list[FloatArray]
    ) -> FloatArray:
        if self.empty:
            return np.full(firing_up.shape[0], self.default)
        value = reduce_points(self.method, *self._points(firing_lo, firing_up, inputs))
        return np.where(np.isnan(value), self.default, value)


class Type2Engine:
    """Exact evaluator of an IT2 rule base (the module docstring says what it computes).

    Built by :class:`fuzzkit.fuzzy.inference.Engine` for an IT2 rule base, which validates it
    first and hands over the type-1 engine's fuzzifier class and rule firing (run once on the
    upper and once on the lower memberships); ``evaluate_flat`` takes 1-D input arrays, NaN
    already replaced.
    """

    def __init__(
        self,
        rb: Type2RuleBase,
        fuzzifier: Callable[[Variable, str], Fuzzifier],
        firing: Callable[[list[FloatArray]], FloatArray],
    ) -> None:
        footprint = rb.footprint
        self.footprint = footprint
        self.upper_fuzzifiers = [fuzzifier(v, rb.out_of_range) for v in rb.inputs]
        lowers = [lower_variable(v, footprint) for v in rb.inputs]
        self.lower_fuzzifiers = [fuzzifier(v, rb.out_of_range) for v, _ in lowers]
        self.lower_heights = [h for _, h in lowers]
        self.firing = firing
        self.outputs: list[_Type2Mamdani | _Type2Sugeno] = [
            _Type2Sugeno(rb, o, footprint) if o.is_sugeno else _Type2Mamdani(rb, o, footprint)
            for o in rb.outputs
        ]
        # every output continuous Mamdani and the firing one the kernel covers: the whole
        # evaluation is one compiled pass per output (fuzzy.type2_kernel)
        self.compiled: FiringLayout | None = None
        if all(isinstance(o, _Type2Mamdani) and o.continuous for o in self.outputs):
            self.compiled = FiringLayout.of(rb, [v for v, _ in lowers], [h for _, h in lowers])

    def firing_intervals(self, flat: list[FloatArray]) -> tuple[FloatArray, FloatArray]:
        """Lower and upper firing strengths of every rule (B, R), weights applied."""
        mus_up = [fz(x) for fz, x in zip(self.upper_fuzzifiers, flat, strict=True)]
        mus_lo = [
            np.minimum(h * fz(x), up)
            for fz, h, x, up in zip(
                self.lower_fuzzifiers, self.lower_heights, flat, mus_up, strict=True
            )
        ]
        return self.firing(mus_lo), self.firing(mus_up)

    def intervals(self, flat: list[FloatArray]) -> dict[str, tuple[FloatArray, FloatArray]]:
        """The Karnik-Mendel interval ``(y_l, y_r)`` of every output (the Sugeno ones over
        their rules' consequent values), whatever the rule base's type reduction."""
        compiled = self._compiled(flat)
        if compiled is not None:
            return {name: (r[:, 0], r[:, 1]) for name, r in compiled.items()}
        f_lo, f_up = self.firing_intervals(flat)
        prepared = [fz.prepare(x) for fz, x in zip(self.upper_fuzzifiers, flat, strict=True)]
        result = {}
        for out in self.outputs:
            if isinstance(out, _Type2Sugeno):
                result[out.name] = out.interval(f_lo, f_up, prepared)
            else:
                result[out.name] = out.interval(f_lo, f_up)
        return result

    def _compiled(self, flat: list[FloatArray]) -> dict[str, FloatArray] | None:
        """``y_l, y_r, A_U, M_U, A_L, M_L, first, last`` (B, 8) of every output, by the
        compiled point path (None where it does not apply)."""
        if self.compiled is None:
            return None
        x = np.stack(flat, axis=1)
        return {
            out.name: out.reduced_points(x, self.compiled)
            for out in self.outputs
            if isinstance(out, _Type2Mamdani)
        }

    def scalar_path(self) -> Callable[[Sequence[float]], list[float]] | None:
        """``values -> outputs`` at one point through the kernel alone, for rule bases the
        compiled path covers with Karnik-Mendel (or EKM) outputs; None otherwise."""
        compiled = self.compiled
        if compiled is None or any(o.method not in ("karnik-mendel", "ekm") for o in self.outputs):
            return None
        outputs = [(o.layout, o.default) for o in self.outputs if isinstance(o, _Type2Mamdani)]
        nan = [math.nan] * len(outputs)

        def point(values: Sequence[float]) -> list[float]:
            x = np.array([values], dtype=np.float64)
            if np.isnan(x).any():
                return nan.copy()  # a NaN input: never a correction
            result = []
            for layout, default in outputs:
                row = evaluate_points(x, compiled, layout)[0]
                y = 0.5 * (float(row[0]) + float(row[1]))
                result.append(default if y != y else y)
            return result

        return point

    def evaluate_flat(self, flat: list[FloatArray]) -> dict[str, FloatArray]:
        """Every output at the points of the 1-D arrays ``flat`` (input order, no NaN)."""
        compiled = self._compiled(flat)
        if compiled is not None:
            return {
                out.name: out.value(compiled[out.name])
                for out in self.outputs
                if isinstance(out, _Type2Mamdani)
            }
        f_lo, f_up = self.firing_intervals(flat)
        prepared = [fz.prepare(x) for fz, x in zip(self.upper_fuzzifiers, flat, strict=True)]
        result = {}
        for out in self.outputs:
            if isinstance(out, _Type2Sugeno):
                result[out.name] = out(f_lo, f_up, prepared)
            else:
                result[out.name] = out(f_lo, f_up)
        return result
