"""The exact engine (Mamdani and Sugeno outputs), vectorised over numpy arrays.

``Engine(rb).evaluate({"e": e, "de": de})`` evaluates a rule base at any number of points at
once (inputs are broadcast together); :func:`evaluate` and :func:`evaluate_point` are the
one-call conveniences.

Exactness
---------
Centroid and bisector are exact for piecewise-linear outputs (closed form,
:mod:`fuzzkit.fuzzy.output_geometry`) and for Gaussian ones under max aggregation (closed form
with erf, :mod:`fuzzkit.fuzzy.gaussian_geometry`); Gaussian ones under a probabilistic sum with
product implication (centroid) are within a proven bound of 1e-12 of the output range (a fixed
Gauss-Legendre rule, :mod:`fuzzkit.fuzzy.smooth_quadrature`), and other smooth ones within 1e-9
of it (an a-priori grid, ``output_geometry.GridGeometry``).


Semantics
---------
* A NaN in any input makes every output NaN at that point: a bad sensor sample never becomes a
  correction. Infinite inputs are clamped like any out-of-range input under ``clamp``.
* ``out_of_range: clamp`` (default) evaluates memberships at the nearest range end;
  ``extend`` evaluates them where the input is.
* Rules sharing a consequent are aggregated with the aggregation operator, never overwritten.
* When no rule fires (zero area or zero total activation) an output takes its ``default``
  (NaN when none is given).
* Weighted average (paper eq. 10): ``sum(a_j c_j) / sum(a_j)`` over the output terms, with
  ``a_j`` the term's activation (its rules' firing strengths aggregated with the aggregation
  operator) and ``c_j`` the term centre of :func:`fuzzkit.fuzzy.membership.centre`.
* Mean of maximum is the midpoint of the smallest and largest of maximum (as in fuzzylite).
* Sugeno outputs (``constant``/``linear`` terms; see :mod:`fuzzkit.fuzzy.sugeno`): every rule
  consequent counts on its own with its weighted firing strength ``w`` and value ``z``;
  ``weighted_average`` is ``sum(w z) / sum(w)``, ``weighted_sum`` is ``sum(w z)``. Implication
  and aggregation do not apply (MATLAB ignores ImpMethod/AggMethod for Sugeno systems, and
  fuzzylite's WeightedAverage/WeightedSum, with aggregation none, read each activated
  term's degree). ``linear``
  terms see the input values the membership functions see (clamped under ``clamp``), and
  the result is not clamped to the output's range. No rule fired (``sum(w) == 0``): default.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import EvaluationError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.fastpath import PolyCentroid, ScalarPath, scalar_input
from fuzzkit.fuzzy.gaussian_geometry import GaussianGeometry
from fuzzkit.fuzzy.gaussian_geometry import applies as gaussian_applies
from fuzzkit.fuzzy.model import Compound, Expression, Proposition, RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import (
    GridGeometry,
    OutputPieces,
    PiecewiseLinearGeometry,
    partition_centroid,
)
from fuzzkit.fuzzy.smooth_quadrature import Quadrature, terms_at_nodes
from fuzzkit.fuzzy.smooth_quadrature import applies as quadrature_applies
from fuzzkit.fuzzy.sugeno import SugenoOutput, SugenoScalarPath, sugeno_scalar_path
from fuzzkit.fuzzy.type2_inference import Type2Engine
from fuzzkit.fuzzy.type2_model import Type2RuleBase

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: The unit of :meth:`Engine.work_per_point`: one operation is one estimated nanosecond of the
#: batch engine (numpy batches of thousands of points). Each output path's cost per unit of
#: its size is calibrated against this project's 2-core machine under load (``_Output.work``,
#: bench/bench_engine_work.py prints the measured against the estimated time), at about twice
#: the most the path measured per unit, so that work / speed over-estimates the time, by a
#: factor that no longer depends on the path (it did by 2-100 when every path shared one
#: constant: the partition's fast centroid was costed as the breakpoint sweep).
OPERATIONS_PER_SECOND = 1e9
#: Nanoseconds per unit of each path's size (see ``_Output.work``): per rule and input (the
#: firing), per grid point and piece (smooth outputs; the probabilistic sum goes through logs),
#: per interval and slot pair (the breakpoint sweep, by defuzzifier), per fast-centroid
#: function, per squared sorted point (Gaussian outputs).
NS_PER_RULE_INPUT = 50
#: Grid outputs stay at 50 ns (3-80 times the measured 0.6-15 ns): a compile of a smooth-output
#: rule base spends time beyond the engine's evaluation that is not counted yet (issue 38:
#: 56 s measured against 34 s estimated on two random rule bases).
NS_PER_GRID_PIECE = 50
NS_PER_SWEEP_SLOT = {"centroid": 600, "bisector": 1500}
NS_PER_SWEEP_SLOT_MAXIMA = 900
NS_FAST_CENTROID = (400, 100)  # per point, and per function
NS_PER_GAUSSIAN_POINT2 = 15
#: Construction, in the same estimated nanoseconds (``Engine.construction_work``): per output
#: (measured 0.7-108 ms), and for a grid output per term its probe and its grid points
#: (measured 66-356 ms for 3-9 terms on grids of 0.2-1 M points).
NS_BUILD_OUTPUT = 80_000_000
NS_BUILD_PROBE_POINT = 250
NS_BUILD_GRID_POINT = 40
_fmin = np.minimum
_fmax = np.maximum


# --------------------------------------------------------------------------- fuzzification


class _Fuzzifier:
    """Memberships of one input variable in all its terms: (B,) -> (B, T)."""

    def __init__(self, var: Variable, policy: str) -> None:
        self.low, self.high = var.low, var.high
        self.clamp = policy == "clamp"
        self.n_terms = len(var.terms)
        self.pl_index = np.array(
            [i for i, t in enumerate(var.terms) if t.is_piecewise_linear], dtype=np.intp
        )
        forms = np.array(
            [membership.trapezoid_form(var.terms[i]) for i in self.pl_index], dtype=np.float64
        ).reshape(-1, 4)
        self.core_start, self.core_end, self.rise, self.fall = (forms[:, k] for k in range(4))
        self.smooth = [(i, t) for i, t in enumerate(var.terms) if not t.is_piecewise_linear]

    def prepare(self, x: FloatArray) -> FloatArray:
        """The input value the terms see: clamped to the range, or bounded under ``extend``."""
        # bare ufuncs rather than np.clip: this runs once per input per call, and the
        # per-call overhead dominates scalar evaluation
        if self.clamp:
            return _fmin(_fmax(x, self.low), self.high)
        return _fmin(_fmax(x, -membership.EXTEND_LIMIT), membership.EXTEND_LIMIT)

    def __call__(self, x: FloatArray) -> FloatArray:
        x = self.prepare(x)
        xc = x[:, None]
        # x is finite and slopes are at most 1e200, so nothing overflows or becomes NaN
        pl = _fmin(
            _fmax(
                _fmin(
                    1.0 + (xc - self.core_start) * self.rise, 1.0 + (self.core_end - xc) * self.fall
                ),
                0.0,
            ),
            1.0,
        )
        if not self.smooth:
            return pl
        out = np.empty((x.shape[0], self.n_terms))
        out[:, self.pl_index] = pl
        for i, term in self.smooth:
            out[:, i] = membership.evaluate_term(term, x)
        return out


# --------------------------------------------------------------------------- rule firing


def _signature(expr: Expression) -> tuple[Any, ...]:
    if isinstance(expr, Proposition):
        return ("is", expr.variable, expr.negated)
    return (expr.op, tuple(_signature(e) for e in expr.operands))


def _leaves(expr: Expression) -> Iterator[Proposition]:
    if isinstance(expr, Proposition):
        yield expr
    else:
        for e in expr.operands:
            yield from _leaves(e)


@dataclass(frozen=True)
class _RuleGroup:
    """Rules of the same antecedent structure, evaluated together as columns."""

    signature: tuple[Any, ...]
    rule_index: IntArray
    leaf_terms: tuple[IntArray, ...]  # per leaf (DFS order): term index for each rule


class _Firing:
    """Firing strengths of all rules, weights applied: memberships -> (B, R)."""

    def __init__(self, rb: RuleBase) -> None:
        self.n_rules = len(rb.rules)
        self.and_op, self.or_op = rb.operators.and_, rb.operators.or_
        self.input_pos = {v.name: i for i, v in enumerate(rb.inputs)}
        by_sig: dict[tuple[Any, ...], list[int]] = {}
        for r, rule in enumerate(rb.rules):
            by_sig.setdefault(_signature(rule.antecedent), []).append(r)
        self.groups: list[_RuleGroup] = []
        for sig, idx in by_sig.items():
            leaves = [list(_leaves(rb.rules[r].antecedent)) for r in idx]
            leaf_terms = tuple(
                np.array(
                    [rb.input(ls[k].variable).term_index(ls[k].term) for ls in leaves],
                    dtype=np.intp,
                )
                for k in range(len(leaves[0]))
            )
            self.groups.append(_RuleGroup(sig, np.array(idx, dtype=np.intp), leaf_terms))
        weights = np.array([rule.weight for rule in rb.rules], dtype=np.float64)
        self.weights: FloatArray | None = None if np.all(weights == 1.0) else weights
        self.single_group_in_order = len(self.groups) == 1 and bool(
            np.array_equal(self.groups[0].rule_index, np.arange(self.n_rules))
        )

    def __call__(self, mus: list[FloatArray]) -> FloatArray:
        if self.single_group_in_order:
            g = self.groups[0]
            out = self._eval(g.signature, iter(g.leaf_terms), mus)
        else:
            out = np.empty((mus[0].shape[0], self.n_rules))
            for g in self.groups:
                out[:, g.rule_index] = self._eval(g.signature, iter(g.leaf_terms), mus)
        if self.weights is not None:
            out = out * self.weights
        return out

    def _eval(
        self, sig: tuple[Any, ...], leaf_terms: Iterator[IntArray], mus: list[FloatArray]
    ) -> FloatArray:
        if sig[0] == "is":
            col = np.take(mus[self.input_pos[sig[1]]], next(leaf_terms), axis=1)
            return 1.0 - col if sig[2] else col
        parts = [self._eval(s, leaf_terms, mus) for s in sig[1]]
        acc = parts[0]
        for p in parts[1:]:
            if sig[0] == "and":
                acc = np.minimum(acc, p) if self.and_op == "min" else acc * p
            else:
                acc = np.maximum(acc, p) if self.or_op == "max" else acc + p - acc * p
        return acc


# --------------------------------------------------------------------------- output stage


class _Output:
    """Defuzzifies one output variable from the rule firing strengths."""

    def __init__(self, rb: RuleBase, out: Variable) -> None:
        self.name = out.name
        self.default = math.nan if out.default is None else float(out.default)
        self.defuzzifier = rb.defuzzifier
        self.pieces = OutputPieces(rb, out)
        self.centres = np.array([membership.centre(t, out.low, out.high) for t in out.terms])
        self.geometry: PiecewiseLinearGeometry | GaussianGeometry | GridGeometry | None = None
        self.fast_centroid: PolyCentroid | None = None
        self.quadrature: Quadrature | None = None  # smooth_quadrature's class
        self.quad_terms: FloatArray | None = None
        if self.defuzzifier != "weighted_average" and not self.pieces.empty:
            if all(t.is_piecewise_linear for t in out.terms):
                geo = PiecewiseLinearGeometry(rb, out, self.pieces)
                self.geometry = geo
                if self.defuzzifier == "centroid":
                    self.fast_centroid = partition_centroid(geo, rb, len(out.terms))
            elif gaussian_applies(rb, out, self.pieces):
                self.geometry = GaussianGeometry(rb, out, self.pieces)
            elif (rule := quadrature_applies(rb, out, self.pieces)) is not None:
                self.quadrature = rule
                self.quad_terms = terms_at_nodes(rule, out, self.pieces)
            else:
                self.geometry = GridGeometry(rb, out, self.pieces)

    def work(self) -> int:
        """Estimated nanoseconds per point (``OPERATIONS_PER_SECOND``): what
        :meth:`Engine.work_per_point` adds up. Measured on the 2-core machine under load, per
        unit of each path's size (the constants are about twice the largest): the grid
        kernel 0.6-4.6 ns per grid point and piece (max, bounded sum) and 12-15 ns
        (probabilistic sum); the breakpoint sweep 220 (centroid), 390 (maxima) and 750 ns
        (bisector) per interval and slot pair; the fast centroid 1.1-1.9 us a point with its
        firing; Gaussian outputs 3-7 ns per squared sorted point."""
        geo = self.geometry
        if self.quadrature is not None:
            return NS_PER_GRID_PIECE * len(self.quadrature.nodes) * self.pieces.n_pieces
        if self.fast_centroid is not None:
            base, per_function = NS_FAST_CENTROID
            return base + per_function * len(self.fast_centroid.functions)
        if isinstance(geo, GridGeometry):
            return NS_PER_GRID_PIECE * len(geo.y) * self.pieces.n_pieces  # every grid point
        if isinstance(geo, PiecewiseLinearGeometry):
            # points sorted in every interval, times numpy's passes over them (the bisector's
            # and the maxima's searches make several)
            per = NS_PER_SWEEP_SLOT.get(self.defuzzifier, NS_PER_SWEEP_SLOT_MAXIMA)
            return per * len(geo.z0) * geo.kmax * geo.kmax
        if isinstance(geo, GaussianGeometry):
            return NS_PER_GAUSSIAN_POINT2 * (2 + len(geo.fixed) + 2 * geo.k * geo.k) ** 2
        return len(self.centres)

    def construction_work(self) -> int:
        """Estimated nanoseconds this output stage took to build (see ``NS_BUILD_OUTPUT``)."""
        geo = self.geometry
        if not isinstance(geo, GridGeometry):
            return NS_BUILD_OUTPUT
        per_term = NS_BUILD_PROBE_POINT * geo.probe_points + NS_BUILD_GRID_POINT * len(geo.y)
        return NS_BUILD_OUTPUT + per_term * self.pieces.n_terms

    def __call__(self, firing: FloatArray, inputs: list[FloatArray]) -> FloatArray:
        b = firing.shape[0]
        if self.pieces.empty:
            return np.full(b, self.default)
        if self.defuzzifier == "weighted_average":
            act = self.pieces.activations(firing)
            tot = act.sum(axis=1)
            with np.errstate(invalid="ignore", divide="ignore"):
                val = (act @ self.centres) / tot
            return np.where(tot > 0, val, self.default)
        levels = self.pieces.levels(firing)
        if self.fast_centroid is not None:
            return self.fast_centroid.centroid(levels, self.default)
        if self.quadrature is not None and self.quad_terms is not None:
            return self._quadrature(self.quadrature, self.quad_terms, levels)
        geo = self.geometry
        if isinstance(geo, PiecewiseLinearGeometry):
            return self._exact(geo, levels)
        if isinstance(geo, GaussianGeometry):
            return self._gaussian(geo, levels)
        if isinstance(geo, GridGeometry):
            return self._grid(geo, levels)
        raise RuntimeError("output stage has no geometry")  # unreachable by construction

    def _quadrature(self, rule: Quadrature, terms: FloatArray, levels: FloatArray) -> FloatArray:
        """Centroid by the proven quadrature (``smooth_quadrature.scaled_fold``), as the
        generated code computes it."""
        top = levels.max(axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(top > 0.0, levels / top, 0.0)
        f = np.zeros((levels.shape[0], terms.shape[1]))
        for p in range(terms.shape[0]):
            x = rel[:, p : p + 1] * terms[p]
            f = f + x - top * f * x
        area = f @ rule.weights
        moment = f @ (rule.weights * rule.nodes)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where((top[:, 0] > 0.0) & (area > 0.0), moment / area, self.default)

    def _exact(self, geo: PiecewiseLinearGeometry, levels: FloatArray) -> FloatArray:
        d = self.defuzzifier
        if d in ("centroid", "bisector"):
            area, moment, *_ = geo.integrals(levels)
            total = area.sum(axis=1)
            ok = total > 1e-300
            if d == "centroid":
                with np.errstate(invalid="ignore", divide="ignore"):
                    val = moment.sum(axis=1) / total
            else:
                val = geo.bisector(levels)
            return np.where(ok, val, self.default)
        height, som, lom = geo.maxima(levels)
        val = {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(d, 0.5 * (som + lom))
        return np.where(height > 0, val, self.default)

    def _gaussian(self, geo: GaussianGeometry, levels: FloatArray) -> FloatArray:
        d = self.defuzzifier
        if d == "centroid":
            return geo.centroid(levels, self.default)
        if d == "bisector":
            return geo.bisector(levels, self.default)
        height, som, lom = geo.maxima(levels)
        val = {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(d, 0.5 * (som + lom))
        return np.where(height > 0, val, self.default)

    def _grid(self, geo: GridGeometry, levels: FloatArray) -> FloatArray:
        # compiled single pass per point: no (points x grid) array, see fuzzy.grid_kernel
        from fuzzkit.fuzzy.grid_kernel import (
            AGGREGATIONS,
            DEFUZZIFIERS,
            IMPLICATIONS,
            grid_defuzzify,
        )

        return grid_defuzzify(
            np.ascontiguousarray(levels, dtype=np.float64),
            geo.piece_mu_t,
            geo.y,
            float(geo.dy),
            IMPLICATIONS[geo.implication],
            AGGREGATIONS[geo.aggregation],
            DEFUZZIFIERS.get(self.defuzzifier, DEFUZZIFIERS["mean_of_maximum"]),
            self.default,
        )


# --------------------------------------------------------------------------- public API


class Engine:
    """Exact evaluator of one rule base; build once, call many times.

    Parameters
    ----------
    rulebase
        A rule base; it is validated (``fuzzkit.fuzzy.validation.ensure_valid``).

    Raises
    ------
    RuleBaseError
        If the rule base is inconsistent.

    Examples
    --------
    >>> import fuzzkit
    >>> eng = fuzzkit.Engine(fuzzkit.load("macvicar_whelan"))
    >>> round(eng.evaluate_point(e=0.0, de=0.0)["du"], 12)
    0.0
    """

    def __init__(self, rulebase: RuleBase) -> None:
        from fuzzkit.fuzzy.validation import ensure_valid

        ensure_valid(rulebase)
        self.rulebase = rulebase
        self.input_names = rulebase.input_names
        self.output_names = rulebase.output_names
        self._fuzzifiers = [_Fuzzifier(v, rulebase.out_of_range) for v in rulebase.inputs]
        self._firing = _Firing(rulebase)
        self._type2: Type2Engine | None = None
        self._outputs: list[_Output | SugenoOutput] = []
        if isinstance(rulebase, Type2RuleBase):
            # interval type-2: the engine beside this one (fuzzy.type2_inference)
            self._type2 = Type2Engine(rulebase, _Fuzzifier, self._firing)
        else:
            self._outputs = [
                SugenoOutput(rulebase, o) if o.is_sugeno else _Output(rulebase, o)
                for o in rulebase.outputs
            ]
        self._linear = any(isinstance(o, SugenoOutput) and o.linear for o in self._outputs)
        self._scalar: (
            ScalarPath | SugenoScalarPath | Callable[[Sequence[float]], list[float]] | None
        )
        if self._type2 is None:
            self._scalar = _scalar_path(rulebase, self._outputs) or sugeno_scalar_path(rulebase)
        else:
            self._scalar = self._type2.scalar_path()

    def construction_work(self) -> int:
        """What building this engine cost, in the estimated nanoseconds of
        :meth:`work_per_point` (a compile's budget counts it with the evaluations)."""
        return sum(o.construction_work() if isinstance(o, _Output) else NS_BUILD_OUTPUT
                   for o in self._outputs)  # fmt: skip

    def work_per_point(self) -> int:
        """Roughly what one point costs the batch engine, in estimated nanoseconds: the rules
        over the inputs, and per output the size of its integration (grid points times
        pieces for smooth terms, intervals times points sorted for piecewise-linear ones,
        functions for the fast centroid), each at its path's calibrated cost. Divided by
        :data:`OPERATIONS_PER_SECOND` it is an upper estimate of the engine's time per point
        (what ``fuzzkit compile`` checks against its time budget before the work)."""
        rules = NS_PER_RULE_INPUT * len(self.rulebase.rules) * max(1, len(self.input_names))
        return rules + sum(o.work() if isinstance(o, _Output) else len(o.inst_rules)
                           for o in self._outputs)  # fmt: skip

    def _coerce(self, inputs: Mapping[str, npt.ArrayLike]) -> list[FloatArray]:
        unknown = sorted(set(inputs) - set(self.input_names))
        missing = [n for n in self.input_names if n not in inputs]
        if unknown or missing:
            parts = []
            if missing:
                parts.append("missing input(s) " + ", ".join(repr(n) for n in missing))
            if unknown:
                parts.append("unknown input(s) " + ", ".join(repr(n) for n in unknown))
            raise EvaluationError(
                f"rule base {self.rulebase.name!r}: {'; '.join(parts)} "
                f"(expected {', '.join(self.input_names)})"
            )
        arrays = []
        for n in self.input_names:
            try:
                arrays.append(np.asarray(inputs[n], dtype=np.float64))
            except (TypeError, ValueError) as exc:
                raise EvaluationError(
                    f"input {n!r}: expected numbers, got {inputs[n]!r:.60}"
                ) from exc
        try:
            return list(np.broadcast_arrays(*arrays))
        except ValueError as exc:
            shapes = ", ".join(
                f"{n}{a.shape}" for n, a in zip(self.input_names, arrays, strict=True)
            )
            raise EvaluationError(f"input shapes do not broadcast together: {shapes}") from exc

    #: Points evaluated together: the intermediate arrays scale with it (firing strengths,
    #: levels, geometry per point), so memory stays bounded whatever the batch size.
    chunk_points = 8192

    def evaluate(self, inputs: Mapping[str, npt.ArrayLike]) -> dict[str, FloatArray]:
        """Evaluate at every point of the broadcast inputs; each output has their shape.

        Large batches are evaluated :attr:`chunk_points` at a time into the result arrays, so
        the working memory does not grow with the batch.
        """
        arrays = self._coerce(inputs)
        shape = arrays[0].shape
        flat = [a.reshape(-1) for a in arrays]
        size = flat[0].size
        step = self.chunk_points
        if size <= step:
            result = self._evaluate_flat(flat)
            return {k: v.reshape(shape) for k, v in result.items()}
        out = {name: np.empty(size) for name in self.output_names}
        for s in range(0, size, step):
            part = self._evaluate_flat([a[s : s + step] for a in flat])
            for name, v in part.items():
                out[name][s : s + step] = v
        return {k: v.reshape(shape) for k, v in out.items()}

    def _evaluate_flat(self, flat: list[FloatArray]) -> dict[str, FloatArray]:
        bad = np.isnan(flat[0])
        for a in flat[1:]:
            bad |= np.isnan(a)
        any_bad = bool(bad.any())
        if any_bad:
            flat = [np.where(bad, 0.0, a) for a in flat]
        if self._type2 is not None:
            got = self._type2.evaluate_flat(flat)
            return {k: np.where(bad, np.nan, v) if any_bad else v for k, v in got.items()}
        mus = [fz(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)]
        firing = self._firing(mus)
        if self._linear:
            flat = [fz.prepare(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)]
        result = {}
        for out in self._outputs:
            val = out(firing, flat)
            result[out.name] = np.where(bad, np.nan, val) if any_bad else val
        return result

    def evaluate_point(
        self, inputs: Mapping[str, float] | None = None, **kw: float
    ) -> dict[str, float]:
        """Evaluate at one point: ``evaluate_point(e=0.3, de=-0.2) -> {"du": ...}``."""
        merged = dict(inputs, **kw) if inputs else kw
        if self._scalar is not None and len(merged) == len(self.input_names):
            try:
                values = [float(merged[n]) for n in self.input_names]
            except (KeyError, TypeError, ValueError):
                values = None
            if values is not None:
                return dict(zip(self.output_names, self._scalar(values), strict=True))
        if len(merged) == len(self.input_names):
            try:
                flat = [np.array([float(merged[n])]) for n in self.input_names]
            except (KeyError, TypeError, ValueError):
                flat = None
            if flat is not None:
                res = self._evaluate_flat(flat)
                return {k: float(v[0]) for k, v in res.items()}
        res2 = self.evaluate(merged)  # slow path: reports what is wrong
        return {k: float(v.reshape(-1)[0]) for k, v in res2.items()}

    def point_function(self, output: str | None = None) -> Callable[..., float]:
        """A plain function ``f(*inputs) -> float`` of one output, inputs in declaration order.

        For control loops that call the engine once per sample: it skips building and reading
        dictionaries, and uses the pure-Python scalar path when the rule base has its shape.
        """
        name = output or self.output_names[0]
        if name not in self.output_names:
            raise EvaluationError(
                f"rule base {self.rulebase.name!r} has no output {name!r} "
                f"(expected one of {', '.join(self.output_names)})"
            )
        idx = self.output_names.index(name)
        scalar = self._scalar
        if scalar is not None:
            return lambda *values: scalar(values)[idx]
        names = self.input_names
        return lambda *values: self.evaluate_point(dict(zip(names, values, strict=True)))[name]

    def centroid_intervals(
        self, inputs: Mapping[str, npt.ArrayLike]
    ) -> dict[str, tuple[FloatArray, FloatArray]]:
        """For an interval type-2 rule base: each output's Karnik-Mendel centroid interval
        ``(y_l, y_r)`` at every point (flattened; NaN where an input is NaN or nothing fires).

        Raises
        ------
        EvaluationError
            For a type-1 rule base (it has no interval).
        """
        if self._type2 is None:
            raise EvaluationError(
                f"rule base {self.rulebase.name!r} is type-1: it has no centroid interval"
            )
        flat = [a.reshape(-1) for a in self._coerce(inputs)]
        bad = np.zeros(flat[0].shape, dtype=bool)
        for a in flat:
            bad |= np.isnan(a)
        flat = [np.where(bad, 0.0, a) for a in flat]
        return {
            name: (np.where(bad, np.nan, lo), np.where(bad, np.nan, hi))
            for name, (lo, hi) in self._type2.intervals(flat).items()
        }

    def firing_strengths(self, inputs: Mapping[str, npt.ArrayLike]) -> FloatArray:
        """Weighted firing strength of every rule at every point, shape (points, rules).

        For an interval type-2 rule base: the upper ends of the firing intervals
        (``fuzzy.type2_inference.Type2Engine.firing_intervals`` gives both).
        """
        flat = [a.reshape(-1) for a in self._coerce(inputs)]
        return self._firing([fz(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)])

    def firing_intervals(
        self, inputs: Mapping[str, npt.ArrayLike]
    ) -> tuple[FloatArray, FloatArray]:
        """For an interval type-2 rule base: the lower and the upper firing strength of every
        rule at every point (weights applied), each of shape (points, rules).

        Raises
        ------
        EvaluationError
            For a type-1 rule base (its firing is :meth:`firing_strengths`).
        """
        if self._type2 is None:
            raise EvaluationError(
                f"rule base {self.rulebase.name!r} is type-1: it has no firing intervals"
            )
        return self._type2.firing_intervals([a.reshape(-1) for a in self._coerce(inputs)])


def _scalar_path(rb: RuleBase, outputs: list[_Output | SugenoOutput]) -> ScalarPath | None:
    """The pure-Python single-point evaluator, when the rule base has its shape."""
    if any(not t.is_piecewise_linear for v in rb.inputs for t in v.terms):
        return None
    if any(not isinstance(o, _Output) or o.fast_centroid is None for o in outputs):
        return None
    pos = {v.name: i for i, v in enumerate(rb.inputs)}
    out_pos = {v.name: i for i, v in enumerate(rb.outputs)}
    table: dict[tuple[int, ...], list[tuple[float, tuple[tuple[int, int], ...]]]] = {}
    for rule in rb.rules:
        ante = rule.antecedent
        props = [ante] if isinstance(ante, Proposition) else list(ante.operands)
        if isinstance(ante, Compound) and ante.op != "and":
            return None
        if not all(isinstance(p, Proposition) and not p.negated for p in props):
            return None
        by_input = {
            pos[p.variable]: rb.input(p.variable).term_index(p.term)
            for p in props
            if isinstance(p, Proposition)
        }
        if len(by_input) != len(props) or len(by_input) != len(rb.inputs):
            return None
        key = tuple(by_input[i] for i in range(len(rb.inputs)))
        cons = tuple(
            (out_pos[c.variable], rb.output(c.variable).term_index(c.term))
            for c in rule.consequents
        )
        table.setdefault(key, []).append((rule.weight, cons))
    inputs = [
        scalar_input(
            v.low,
            v.high,
            rb.out_of_range == "clamp",
            [membership.trapezoid_form(t) for t in v.terms],
            [p for t in v.terms for p in membership.breakpoints(t)],
        )
        for v in rb.inputs
    ]
    outs = []
    for o, var in zip(outputs, rb.outputs, strict=True):
        if not isinstance(o, _Output) or o.fast_centroid is None:  # checked above (for mypy)
            return None
        outs.append((o.fast_centroid, len(var.terms), o.default))
    return ScalarPath(inputs, table, rb.operators.and_ == "product", outs)


_ENGINES: dict[int, tuple[RuleBase, Engine]] = {}


def engine_for(rulebase: RuleBase) -> Engine:
    """A cached Engine for ``rulebase`` (keyed by identity; the model is immutable)."""
    hit = _ENGINES.get(id(rulebase))
    if hit is not None and hit[0] is rulebase:
        return hit[1]
    eng = Engine(rulebase)
    if len(_ENGINES) > 64:
        _ENGINES.clear()
    _ENGINES[id(rulebase)] = (rulebase, eng)
    return eng


def evaluate(rulebase: RuleBase, inputs: Mapping[str, npt.ArrayLike]) -> dict[str, FloatArray]:
    """Evaluate ``rulebase`` at the broadcast inputs: ``{name: array}`` -> ``{output: array}``."""
    return engine_for(rulebase).evaluate(inputs)


def evaluate_point(
    rulebase: RuleBase, inputs: Mapping[str, float] | None = None, **kw: float
) -> dict[str, float]:
    """Evaluate ``rulebase`` at one point; returns ``{output: float}``."""
    return engine_for(rulebase).evaluate_point(inputs, **kw)


# The output-stage building blocks, for code generators that emit the same breakpoint sweep
# (``fuzzkit.codegen.exact``); they live in :mod:`fuzzkit.fuzzy.output_geometry`.
__all__ = [
    "Engine",
    "OutputPieces",
    "PiecewiseLinearGeometry",
    "engine_for",
    "evaluate",
    "evaluate_point",
    "partition_centroid",
]
