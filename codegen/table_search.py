"""Table search: place breakpoints, sample the exact engine, fit node values, certify the bound.

:func:`make_table` finds the smallest :class:`~fuzzkit.codegen.lookup_table.LookupTable` meeting a
tolerance (or builds one at a given resolution); :func:`build_table` builds one table for given
breakpoints. How breakpoints are placed and the bound measured is described in
:mod:`fuzzkit.codegen.lookup_table`.

Size: about 900 lines, one pipeline (breakpoints -> reference samples -> fitted values ->
certified bound -> search over resolutions) whose stages share private helpers; the reference
evaluators (:class:`ReferenceEvaluator` and the metered, compiled and chunked ones) are the
part that could stand alone.
"""

from __future__ import annotations

import dataclasses
import decimal
import itertools
import math
from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from fuzzkit.codegen.budget import SEARCH_SECONDS, EngineBudget
from fuzzkit.codegen.edge_floor import chord_floor
from fuzzkit.codegen.lookup_table import (
    CHECK_FACTOR,
    DEFAULT_MAX_POINTS,
    DEFAULT_TOLERANCE,
    GRADING,
    MAX_BREAKPOINTS,
    MIN_BREAKPOINTS,
    NUMBER_TYPES,
    Q15_ONE,
    Q15_RECIP_BITS,
    REFINE_CELLS,
    REFINE_FACTOR,
    REFINE_SHARE,
    Evaluator,
    FloatArray,
    IntArray,
    LookupTable,
    NumberType,
    Q15Layout,
    Q15ResolutionError,
    _is_uniform,
    _locate_float,
    bound_margin,
    percent,
    quantize_q15,
)
from fuzzkit.codegen.progress import ProgressFn
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.membership import breakpoints
from fuzzkit.fuzzy.model import RuleBase, Variable

#: Points per exact-engine call when progress is reported.
PROGRESS_CHUNK = 1 << 16

#: Diagonal errors (share of the output range) closer than this are a tie.
SPLIT_TIE = 1e-12

#: Fitted node values smaller than this share of the output range are solver noise: set to 0.
SNAP_TO_ZERO = 1e-12


def knots(var: Variable) -> FloatArray:
    """Where ``var``'s membership functions have kinks inside its range, plus the range ends."""
    pts = {float(var.low), float(var.high)}
    for term in var.terms:
        if term.is_piecewise_linear:
            pts.update(float(p) for p in breakpoints(term) if var.low < p < var.high)
    ordered = np.array(sorted(pts), dtype=np.float64)
    # Knots closer than a millionth of the range would make needlessly tiny cells.
    keep = np.concatenate(([True], np.diff(ordered) > 1e-6 * (var.high - var.low)))
    keep[-1] = True
    merged = ordered[keep]
    if len(merged) >= 2 and merged[-2] >= merged[-1]:
        merged = np.delete(merged, -2)
    return merged


def _allocate(lengths: FloatArray, pieces: int) -> IntArray:
    """Split ``pieces`` sub-intervals over intervals of ``lengths`` (each >= 1), evenly."""
    n = len(lengths)
    alloc: IntArray = np.maximum(1, np.floor(lengths / lengths.sum() * pieces)).astype(np.int64)
    while alloc.sum() < pieces:
        alloc[int(np.argmax(lengths / alloc))] += 1
    while alloc.sum() > pieces:
        spacing = np.where(alloc > 1, lengths / np.maximum(alloc - 1, 1), np.inf)
        alloc[int(np.argmin(spacing))] -= 1
    if n and alloc.min() < 1:  # pragma: no cover - guarded by the caller
        raise CodegenError("internal: breakpoint allocation failed")
    return alloc


def axis_breakpoints(var: Variable, count: int) -> FloatArray:
    """``count`` breakpoints over ``var``'s range, on its knots when ``count`` allows it."""
    if count < MIN_BREAKPOINTS:
        raise CodegenError(
            f"input {var.name}: a table needs at least {MIN_BREAKPOINTS} breakpoints, got {count}"
        )
    ks = knots(var)
    if count - 1 < len(ks) - 1:
        return np.linspace(var.low, var.high, count)
    alloc = _allocate(np.diff(ks), count - 1)
    graded = any(t.is_piecewise_linear for t in var.terms)
    parts = []
    for i in range(len(ks) - 1):
        u = np.linspace(0.0, 1.0, int(alloc[i]) + 1)[:-1]
        if graded:
            u = _grade(u)
        parts.append(ks[i] + (ks[i + 1] - ks[i]) * u)
    return np.concatenate([*parts, [ks[-1]]])


def _grade(u: FloatArray) -> FloatArray:
    """Map [0, 1] to itself with nodes crowded towards both ends, symmetrically.

    Near a knot of piecewise-linear terms (where one label holds with degree ~1 and its
    neighbours start to fire) a centroid surface curves like r**1.5 rather than r**2, so even
    spacing wastes nodes in the middle; ``u**p / (u**p + (1-u)**p)`` with p = GRADING halved
    the MacVicar-Whelan bound for the same node count (p = 1, 2, 3 were worse). Symmetry keeps
    the cell diagonals on the label cells' diagonals, where AND = min has its creases.
    """
    up = u**GRADING
    result: FloatArray = up / (up + (1.0 - u) ** GRADING)
    return result


def _axis_count_for_spacing(var: Variable, cells_per_range: int) -> int:
    """Breakpoints for cells no wider than range/``cells_per_range``, on and between knots."""
    ks = knots(var)
    h = (var.high - var.low) / cells_per_range
    pieces = np.ceil(np.diff(ks) / h - 1e-9).astype(np.int64)
    # An even number of pieces puts a node midway between knots, where adjacent labels cross
    # at 0.5 and the aggregated output changes shape (a crease of the surface).
    pieces = np.maximum(2, pieces + pieces % 2)
    return int(pieces.sum()) + 1


def _check_grid_axis(bp: FloatArray, factor: int) -> FloatArray:
    steps = np.linspace(0.0, 1.0, factor + 1)[:-1]
    inner = (bp[:-1, None] + (bp[1:] - bp[:-1])[:, None] * steps[None, :]).ravel()
    return np.concatenate([inner, bp[-1:]])


#: Points per evaluator call: keeps the engine's (points x intervals x pieces) work arrays small.
CHUNK_POINTS = 16_384
#: Largest check grid a --resolution may ask for (grid arrays of about 100 bytes per point:
#: this keeps a compile well under 1 GB).
MAX_CHECK_POINTS = 1 << 22


def _engine_evaluator(rb: RuleBase) -> Evaluator:
    """The exact engine, each call charged to a :class:`~fuzzkit.codegen.budget.EngineBudget`
    of ``SEARCH_SECONDS`` before it runs (chunked callers charge each chunk)."""
    from fuzzkit.fuzzy.inference import Engine

    engine = Engine(rb)
    budget = EngineBudget(engine, "the table search", SEARCH_SECONDS)

    def evaluate(inputs: Mapping[str, FloatArray]) -> Mapping[str, FloatArray]:
        budget.charge(math.prod(np.broadcast_shapes(*[np.shape(v) for v in inputs.values()])))
        return engine.evaluate(inputs)

    return evaluate


class _Metered:
    """An evaluator that evaluates in chunks of ``PROGRESS_CHUNK`` points and reports each.

    The exact engine is pointwise, so chunking does not change any value (a test holds it).
    :meth:`sharing` wraps another evaluator that counts into the same total (node values and
    check grids come from different evaluators, see :class:`ReferenceEvaluator`).
    """

    def __init__(self, evaluate: Evaluator, progress: ProgressFn, task: str, total: int) -> None:
        self.evaluate = evaluate
        self.progress = progress
        self.task = task
        self._count = [0, total]  # done, total: shared with the evaluators made by sharing()

    @property
    def done(self) -> int:
        return self._count[0]

    @done.setter
    def done(self, value: int) -> None:
        self._count[0] = value

    @property
    def total(self) -> int:
        return self._count[1]

    @total.setter
    def total(self, value: int) -> None:
        self._count[1] = value

    def sharing(self, evaluate: Evaluator) -> _Metered:
        """``evaluate``, metered into this evaluator's count."""
        other = _Metered(evaluate, self.progress, self.task, self.total)
        other._count = self._count
        return other

    def __call__(self, inputs: Mapping[str, FloatArray]) -> Mapping[str, FloatArray]:
        names = list(inputs)
        arrays = np.broadcast_arrays(*(np.asarray(inputs[n], dtype=np.float64) for n in names))
        shape = arrays[0].shape
        flat = [a.ravel() for a in arrays]
        size = flat[0].size
        self.total = max(self.total, self.done + size)
        parts: dict[str, list[FloatArray]] = {}
        for start in range(0, size, PROGRESS_CHUNK):
            stop = min(size, start + PROGRESS_CHUNK)
            chunk = self.evaluate({n: f[start:stop] for n, f in zip(names, flat, strict=True)})
            for key, value in chunk.items():
                arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (stop - start,))
                parts.setdefault(key, []).append(arr)
            self.done += stop - start
            self.progress(self.task, self.done, self.total)
        return {k: np.concatenate(v).reshape(shape) for k, v in parts.items()}


def _compiled_exact_evaluator(rb: RuleBase) -> Evaluator | None:
    """The exact method compiled to a shared library (double), or None without a compiler.

    Its results are the engine's to rounding (``fuzzkit.codegen.exact.ROUNDING_BOUND``, tested
    on every shipped rule base and a random family), about 100x faster per point than the
    vectorised engine on breakpoint-heavy outputs (bisector, mean of maximum).
    """
    from fuzzkit.codegen.exact import emit_exact, unsupported_reason
    from fuzzkit.codegen.toolchain import CompiledTable, find_compiler
    from fuzzkit.errors import ToolchainError

    if unsupported_reason(rb, "double") is not None or find_compiler() is None:
        return None
    try:
        files = emit_exact(rb, "c", "double")
        lib = CompiledTable(files, rb.name, "double", len(rb.inputs), len(rb.outputs), fpi=False)
    except (CodegenError, ToolchainError):
        return None
    lib.close()  # the library stays loaded; only the build folder goes
    names = [v.name for v in rb.inputs]
    outs = [v.name for v in rb.outputs]

    def evaluate(inputs: Mapping[str, FloatArray]) -> Mapping[str, FloatArray]:
        arrays = np.broadcast_arrays(*[np.asarray(inputs[n], dtype=np.float64) for n in names])
        pts = np.column_stack([a.reshape(-1) for a in arrays])
        got = lib.eval_batch(pts)
        return {o: got[:, k].reshape(arrays[0].shape) for k, o in enumerate(outs)}

    return evaluate


def _chunked(rb: RuleBase, evaluate: Evaluator) -> Evaluator:
    """``evaluate`` in chunks of CHUNK_POINTS (bounded memory; progress is the caller's)."""
    names = [v.name for v in rb.inputs]
    outs = [v.name for v in rb.outputs]

    def run(inputs: Mapping[str, FloatArray]) -> Mapping[str, FloatArray]:
        arrays = np.broadcast_arrays(*[np.asarray(inputs[n], dtype=np.float64) for n in names])
        flat = [a.reshape(-1) for a in arrays]
        total = flat[0].size
        result = {o: np.empty(total) for o in outs}
        for s in range(0, total, CHUNK_POINTS):
            part = evaluate({n: f[s : s + CHUNK_POINTS] for n, f in zip(names, flat, strict=True)})
            for o in outs:
                result[o][s : s + CHUNK_POINTS] = np.asarray(part[o], dtype=np.float64).reshape(-1)
        return {o: v.reshape(arrays[0].shape) for o, v in result.items()}

    return run


#: Check-grid calls with more points than this go to the compiled exact method when a C
#: compiler is available (smaller ones cost little either way).
ENGINE_POINTS = 4096


class ReferenceEvaluator:
    """The engine for node values, the compiled exact method for dense check grids; chunked.

    Node values (:attr:`nodes`) come from the engine itself, so that they are its values bit
    for bit (zeros on the knot lattice stay exact zeros). The check grids certifying the bound
    are 16 to 64 times larger; there the compiled exact method (equal to the engine up to
    rounding, about 1e-14 of the range) keeps a compile within seconds (bisector and mean of
    maximum cost the vectorised engine about 20 us a point). Without a C compiler the engine
    does everything.
    """

    def __init__(self, rb: RuleBase) -> None:
        self.rb = rb
        self.nodes = _chunked(rb, _engine_evaluator(rb))
        self._compiled: list[Evaluator | None] = []

    def __call__(self, inputs: Mapping[str, FloatArray]) -> Mapping[str, FloatArray]:
        size = np.broadcast_shapes(*[np.shape(v) for v in inputs.values()])
        if math.prod(size) <= ENGINE_POINTS:
            return self.nodes(inputs)
        if not self._compiled:  # built once, on first need
            fast = _compiled_exact_evaluator(self.rb)
            self._compiled.append(None if fast is None else _chunked(self.rb, fast))
        return (self._compiled[0] or self.nodes)(inputs)


def _default_evaluator(rb: RuleBase) -> Evaluator:
    return ReferenceEvaluator(rb)


def check_factor_for(counts: Sequence[int], check_factor: int = CHECK_FACTOR) -> int:
    """How much denser than the table its bound is certified (per axis)."""
    factor = 4 * math.ceil(max(check_factor, {1: 16, 2: 8, 3: 8}[len(counts)]) / 4)
    # Three inputs: 8x costs 512 check points per cell, so large tables fall back to 4x (the
    # contract's minimum), which the margin then has to cover.
    if len(counts) == 3 and math.prod(8 * (n - 1) + 1 for n in counts) > 4_000_000:
        factor = 4 * math.ceil(check_factor / 4)
    return factor


def check_points_for(counts: Sequence[int]) -> int:
    """Points of the check grid of a table with ``counts`` breakpoints per input."""
    factor = check_factor_for(counts)
    return math.prod(factor * (n - 1) + 1 for n in counts)


def _sample(
    rb: RuleBase, evaluate: Evaluator, axes: Sequence[FloatArray]
) -> tuple[FloatArray, ...]:
    grids = np.meshgrid(*axes, indexing="ij")
    result = evaluate({v.name: g for v, g in zip(rb.inputs, grids, strict=True)})
    outs = []
    for var in rb.outputs:
        arr = np.broadcast_to(np.asarray(result[var.name], dtype=np.float64), grids[0].shape)
        outs.append(np.array(arr))
    return tuple(outs)


def _q15_layout(
    rb: RuleBase, breakpoints: Sequence[FloatArray]
) -> tuple[Q15Layout, tuple[FloatArray, ...]]:
    """Snap breakpoints to Q15 codes; returns the layout and the snapped real breakpoints."""
    in_scale = tuple(max(abs(v.low), abs(v.high)) for v in rb.inputs)
    out_scale = tuple(max(abs(v.low), abs(v.high)) for v in rb.outputs)
    q_low, q_high, q_bps, recips, real_bps = [], [], [], [], []
    for var, bp, scale in zip(rb.inputs, breakpoints, in_scale, strict=True):
        lo = int(np.clip(math.ceil(var.low / scale * Q15_ONE - 1e-9), -32768, 32767))
        hi = int(np.clip(math.floor(var.high / scale * Q15_ONE + 1e-9), -32768, 32767))
        qb = np.clip(np.rint(bp / scale * Q15_ONE), lo, hi).astype(np.int64)
        if np.any(np.diff(qb) <= 0):
            raise Q15ResolutionError(
                f"input {var.name}: {len(bp)} breakpoints are too close for Q15 "
                "(two round to the same code); use fewer breakpoints or a float type",
                var.name,
                len(bp),
                hi - lo + 1,
            )
        widths = np.diff(qb)
        q_low.append(lo)
        q_high.append(hi)
        q_bps.append(qb)
        recips.append(np.rint((1 << Q15_RECIP_BITS) / widths).astype(np.int64))
        real_bps.append(qb.astype(np.float64) * (scale / Q15_ONE))
    layout = Q15Layout(
        in_scale, out_scale, tuple(q_low), tuple(q_high), tuple(q_bps), tuple(recips)
    )
    return layout, tuple(real_bps)


def _float32_breakpoints(rb: RuleBase, breakpoints: Sequence[FloatArray]) -> tuple[FloatArray, ...]:
    """Non-uniform breakpoints rounded to float32, the values the generated float C stores.

    The table is then sampled where the C's nodes really are (a knot at 1000.3 is a node at
    1000.29998779 in float32). Uniform axes keep their float64 nodes: the C never stores
    them, it computes ``(x - low) * (1 / step)``, which :meth:`LookupTable.interpolate`
    reproduces in float32.
    """
    snapped = []
    for var, bp in zip(rb.inputs, breakpoints, strict=True):
        if _is_uniform(bp):
            snapped.append(bp)
            continue
        bp32 = bp.astype(np.float32).astype(np.float64)
        if np.any(np.diff(bp32) <= 0):
            raise CodegenError(
                f"input {var.name}: {len(bp)} breakpoints are too close for float "
                f"(two round to the same float32 value in [{var.low:g}, {var.high:g}]); "
                "use a larger --tolerance or --type double"
            )
        snapped.append(bp32)
    return tuple(snapped)


def round_up(value: float, digits: int = 3) -> float:
    """``value`` rounded up to ``digits`` significant digits: a printed bound never shrinks."""
    if not (math.isfinite(value) and value > 0):
        return value
    exact = decimal.Decimal(value)
    step = decimal.Decimal(1).scaleb(exact.adjusted() - (digits - 1))
    # float() of a decimal >= value is the nearest double to it, so it is >= value too.
    return float(exact.quantize(step, rounding=decimal.ROUND_CEILING))


def _refine_worst_cells(
    rb: RuleBase,
    table: LookupTable,
    evaluator: Evaluator,
    approx: Sequence[FloatArray],
    exact: Sequence[FloatArray],
    factor: int,
    splits: npt.NDArray[np.uint8] | None,
    measured: tuple[float, ...],
) -> tuple[float, ...]:
    """The check-grid maxima, raised by sampling the worst 2-D cells ``REFINE_FACTOR`` x.

    Creases of the surface (bounded-sum saturation, max aggregation) cross cells at any
    angle, and near a crease the error peaks like |distance|, so a grid can miss the peak by
    its slope times half the spacing (seen: 7 % on gaussian5 at 8x). Every cell whose check
    error comes within ``REFINE_SHARE`` of the maximum (at most ``REFINE_CELLS``, worst first)
    is sampled again much more densely, which leaves the margin only a fraction of a percent.
    """
    n0, n1 = (len(bp) - 1 for bp in table.breakpoints)
    err = np.zeros((n0, n1))
    for a, e, m in zip(approx, exact, measured, strict=True):
        if m <= 0:
            continue
        diff = np.abs(a - e) / m
        # A cell's points, edges included: the grid point (i*f + r, j*f + c), r, c in 0..f.
        for r0 in (0, 1):
            for c0 in (0, 1):
                part = diff[r0 : r0 + n0 * factor, c0 : c0 + n1 * factor]
                err = np.maximum(err, part.reshape(n0, factor, n1, factor).max(axis=(1, 3)))
    order = np.argsort(err.ravel())[::-1][:REFINE_CELLS]
    order = order[err.ravel()[order] >= REFINE_SHARE]
    u = np.linspace(0.0, 1.0, REFINE_FACTOR + 1)
    b0, b1 = table.breakpoints
    xs0, xs1 = [], []
    for cell in order:
        i, j = divmod(int(cell), n1)
        g0, g1 = np.meshgrid(
            b0[i] + (b0[i + 1] - b0[i]) * u, b1[j] + (b1[j + 1] - b1[j]) * u, indexing="ij"
        )
        xs0.append(g0.ravel())
        xs1.append(g1.ravel())
    if not xs0:
        return measured
    pts = [np.concatenate(xs0), np.concatenate(xs1)]
    if table.number_type == "float":
        pts = [p.astype(np.float32).astype(np.float64) for p in pts]
    result = evaluator({v.name: p for v, p in zip(rb.inputs, pts, strict=True)})
    approx_r = table.interpolate_with(pts, splits)
    return tuple(
        max(m, float(np.max(np.abs(a - np.asarray(result[v.name], dtype=np.float64)))))
        for m, a, v in zip(measured, approx_r, rb.outputs, strict=True)
    )


def _float32_near(knot_values: FloatArray, axis: FloatArray) -> FloatArray:
    """The float32 values within two steps of every knot, inside ``axis``, not yet in it."""
    k32 = knot_values.astype(np.float32)
    near = [k32]
    for direction in (-np.inf, np.inf):
        step = k32
        for _ in range(2):
            step = np.nextafter(step, np.float32(direction))
            near.append(step)
    extra = np.unique(np.concatenate(near).astype(np.float64))
    keep = (extra >= axis[0]) & (extra <= axis[-1]) & ~np.isin(extra, axis)
    result: FloatArray = extra[keep]
    return result


def _store(
    values: Sequence[FloatArray], number_type: NumberType, layout: Q15Layout | None
) -> tuple[npt.NDArray[np.generic], ...]:
    if number_type == "float":
        return tuple(v.astype(np.float32) for v in values)
    if number_type == "double":
        return tuple(v.astype(np.float64) for v in values)
    if layout is None:  # pragma: no cover - built together by the caller
        raise CodegenError("internal: q15 table without layout")
    return tuple(
        quantize_q15(v, s).astype(np.int16) for v, s in zip(values, layout.out_scale, strict=True)
    )


def _table_breakpoints(
    rb: RuleBase, counts: Sequence[int], number_type: NumberType
) -> tuple[Q15Layout | None, tuple[FloatArray, ...]]:
    """The breakpoints a table of ``counts`` stores (float32- or Q15-rounded), its Q15 layout."""
    bps = tuple(axis_breakpoints(v, int(n)) for v, n in zip(rb.inputs, counts, strict=True))
    if number_type == "q15":
        return _q15_layout(rb, bps)
    if number_type == "float":
        return None, _float32_breakpoints(rb, bps)
    return None, bps


def _check_axes(
    bps: Sequence[FloatArray], factor: int, number_type: NumberType
) -> list[FloatArray]:
    axes = [_check_grid_axis(bp, factor) for bp in bps]
    if number_type == "float":
        # A float C function only ever sees float32 inputs: certify it on such inputs (the
        # rounding is monotone, so the grid keeps its shape per cell).
        axes = [a.astype(np.float32).astype(np.float64) for a in axes]
    return axes


def build_table(
    rb: RuleBase,
    counts: Sequence[int],
    *,
    number_type: NumberType = "float",
    tolerance: float | None = None,
    evaluate: Evaluator | None = None,
    check_factor: int = CHECK_FACTOR,
    fit: bool = True,
    progress: ProgressFn | None = None,
) -> LookupTable:
    """Sample ``rb`` with ``counts[i]`` breakpoints on input ``i`` and measure the bound.

    ``tolerance`` (fraction of each output range) is only recorded here (as absolute values
    per output; ``()`` when None); :func:`make_table` enforces it. ``evaluate`` defaults to
    the exact engine. ``fit`` (two inputs) stores least-squares node values instead of the
    exact samples where that is safe (see ``_fit_values``); ``values`` always holds the
    samples. ``progress`` is told the points evaluated (see :data:`ProgressFn`).
    """
    _check_rule_base(rb, number_type)
    if check_factor < 4:
        raise CodegenError(f"check_factor must be at least 4, got {check_factor}")
    if len(counts) != len(rb.inputs):
        raise CodegenError(f"expected {len(rb.inputs)} breakpoint counts, got {len(counts)}")
    evaluator = evaluate if evaluate is not None else _default_evaluator(rb)
    layout, bps = _table_breakpoints(rb, counts, number_type)
    # The check grid depends on the breakpoints only: size it first, so that progress is
    # reported against the real total. A multiple of 4, so the 4x sub-grid the 2-D diagonals
    # are chosen on is part of it.
    sizes = [len(b) for b in bps]
    factor = check_factor_for(sizes, check_factor)
    # Node values come from the engine itself (bit for bit), check grids maybe from the
    # compiled exact method (see ReferenceEvaluator).
    node_evaluator = evaluator.nodes if isinstance(evaluator, ReferenceEvaluator) else evaluator
    if progress is not None:
        checks = math.prod(factor * (n - 1) + 1 for n in sizes)
        shape = "x".join(map(str, sizes))
        metered = _Metered(evaluator, progress, f"{shape} table", math.prod(sizes) + checks)
        evaluator, node_evaluator = metered, metered.sharing(node_evaluator)
    values = _sample(rb, node_evaluator, bps)
    for var, vals in zip(rb.outputs, values, strict=True):
        if not np.all(np.isfinite(vals)):
            bad = np.argwhere(~np.isfinite(vals))[0]
            where = ", ".join(f"{v.name}={bps[a][bad[a]]:.6g}" for a, v in enumerate(rb.inputs))
            raise CodegenError(
                f"output {var.name} is undefined at {where} (no rule fires there); "
                "add rules covering it or give the output a default"
            )
        if layout is not None:
            _check_q15_full_scale(var, vals)
    stored = _store(values, number_type, layout)
    table = LookupTable(
        rule_base_name=rb.name,
        input_names=rb.input_names,
        output_names=rb.output_names,
        input_ranges=tuple((float(v.low), float(v.high)) for v in rb.inputs),
        output_ranges=tuple((float(v.low), float(v.high)) for v in rb.outputs),
        breakpoints=bps,
        values=values,
        stored=stored,
        number_type=number_type,
        q15=layout,
        bound=(),
        tolerance=()
        if tolerance is None
        else tuple(tolerance * (v.high - v.low) for v in rb.outputs),
        check_points=0,
    )
    check_axes = _check_axes(bps, factor, number_type)
    exact = _sample(rb, evaluator, check_axes)
    grids = np.meshgrid(*check_axes, indexing="ij")
    splits = _choose_splits(table, grids, exact, factor) if len(bps) == 2 else None
    fitted = False
    if fit and splits is not None:
        with_splits = dataclasses.replace(table, splits=splits)
        values_fit = _fit_values(rb, with_splits, grids, exact, factor)
        if values_fit is not None:
            table = dataclasses.replace(table, stored=_store(values_fit, number_type, layout))
            fitted = True
    approx = table.interpolate_with(grids, splits)
    measured = tuple(float(np.max(np.abs(a - e))) for a, e in zip(approx, exact, strict=True))
    if len(bps) == 2:
        measured = _refine_worst_cells(
            rb, table, evaluator, approx, exact, factor, splits, measured
        )
    if number_type == "float":
        # A knot float32 cannot hold lies inside a cell, and the largest error sits on the
        # first float32 values past it: check the lines through them too.
        for axis, var in enumerate(rb.inputs):
            near = _float32_near(knots(var), check_axes[axis])
            if near.size == 0:
                continue
            axes_k = [near if a == axis else ax for a, ax in enumerate(check_axes)]
            exact_k = _sample(rb, evaluator, axes_k)
            approx_k = table.interpolate_with(np.meshgrid(*axes_k, indexing="ij"), splits)
            measured = tuple(
                max(m, float(np.max(np.abs(a - e))))
                for m, a, e in zip(measured, approx_k, exact_k, strict=True)
            )
    return dataclasses.replace(
        table,
        bound=tuple(round_up(m * bound_margin(factor)) for m in measured),
        measured=measured,
        check_factor=factor,
        check_points=int(grids[0].size),
        splits=splits,
        fitted=fitted,
    )


def _fit_values(
    rb: RuleBase,
    table: LookupTable,
    grids: Sequence[FloatArray],
    exact: Sequence[FloatArray],
    factor: int,
) -> tuple[FloatArray, ...] | None:
    """Node values minimising the squared error on the 4x sub-grid (2 inputs), or None.

    Exact samples at the nodes are not the best table: between nodes a curved surface lies
    on one side of its linear interpolant, so shifting the nodes by about half the error
    halves the largest error (seen: 2x on MacVicar-Whelan, i.e. half the table for the same
    bound). Nodes on the knot lattice keep their exact values (so e = de = 0 still gives
    exactly the engine's output there: no drift of an integrating loop at equilibrium). If
    the fit would break a monotonicity the samples have along an axis (a non-monotone table
    can make a force loop limit-cycle), or the solve fails: None (keep the samples). None of
    the shipped centroid surfaces is monotone, so none loses the fit to that rule.
    """
    import scipy.sparse as sparse
    import scipy.sparse.linalg as sparse_linalg

    step = factor // 4
    pts = [g[::step, ::step].ravel() for g in grids]
    idx, frac = _locate_float(table.breakpoints, pts)
    i, j = idx
    t0, t1 = frac
    n1 = len(table.breakpoints[1])
    splits = table.splits
    if splits is None:  # pragma: no cover - only called with splits
        return None
    # The same corner weights _combine uses: (1 - hi) w00 + (hi - lo) vm + lo w11.
    anti = splits[i, j].astype(bool)
    s0 = np.where(anti, 1.0 - t0, t0)
    lower = s0 >= t1
    hi = np.where(lower, s0, t1)
    lo = np.where(lower, t1, s0)
    k = i * n1 + j
    c00, c10, c01, c11 = k, k + n1, k + 1, k + n1 + 1
    w00 = np.where(anti, c10, c00)
    vm = np.where(lower, np.where(anti, c00, c10), np.where(anti, c11, c01))
    w11 = np.where(anti, c01, c11)
    rows = np.repeat(np.arange(k.size), 3)
    a = sparse.csr_matrix(
        (
            np.column_stack([1.0 - hi, hi - lo, lo]).ravel(),
            (rows, np.column_stack([w00, vm, w11]).ravel()),
        ),
        shape=(k.size, table.n_points),
    )
    # (A float table's knots are rounded to float32 like its other breakpoints.)
    on_knot = [
        np.isin(bp, knots(v)) | np.isin(bp, knots(v).astype(np.float32).astype(np.float64))
        for bp, v in zip(table.breakpoints, rb.inputs, strict=True)
    ]
    pinned = np.logical_and.outer(on_knot[0], on_knot[1]).ravel()
    free = ~pinned
    a_free = a[:, free]
    a_pin = a[:, pinned]
    normal = (a_free.T @ a_free).tocsc()
    fitted = []
    for vals, ex, out in zip(table.values, exact, rb.outputs, strict=True):
        flat = vals.ravel()
        rhs = ex[::step, ::step].ravel() - a_pin @ flat[pinned]
        try:
            sol = sparse_linalg.spsolve(normal, a_free.T @ rhs)
        except RuntimeError:  # singular normal equations: keep the samples
            return None
        new_flat = flat.copy()
        new_flat[free] = sol
        new: FloatArray = new_flat.reshape(vals.shape)
        if not np.all(np.isfinite(new)):
            return None
        # The solver's rounding leaves ~1e-16 where the surface is 0 by symmetry; that noise
        # depends on the BLAS and numpy release, so it is snapped to exactly 0 (far below any
        # bound, which is certified afterwards on the stored values).
        new[np.abs(new) <= SNAP_TO_ZERO * (out.high - out.low)] = 0.0
        # A fit that breaks a monotonicity the samples have is not used (keep the samples).
        span = float(np.ptp(vals)) or 1.0
        for axis in (0, 1):
            d_old = np.diff(vals, axis=axis)
            d_new = np.diff(new, axis=axis)
            for sign in (1.0, -1.0):
                if np.all(sign * d_old >= -1e-12 * span) and not np.all(
                    sign * d_new >= -1e-12 * span
                ):
                    return None
        fitted.append(new)
    return tuple(fitted)


def _choose_splits(
    table: LookupTable,
    grids: Sequence[FloatArray],
    exact: Sequence[FloatArray],
    factor: int,
) -> npt.NDArray[np.uint8]:
    """Per 2-D cell, the diagonal whose two triangles fit the exact surface better.

    Chosen on the 4x sub-grid of the check grid only, so three quarters of the points that
    certify the bound played no part in the choice.
    """
    k = 4
    step = factor // k
    sub = [g[::step, ::step] for g in grids]
    n0, n1 = (len(bp) - 1 for bp in table.breakpoints)
    worst = []
    for choice in (0, 1):
        trial = np.full((n0, n1), choice, dtype=np.uint8)
        approx = table.interpolate_with(sub, trial)
        err = np.zeros((n0, n1))
        for a, e, (lo, hi) in zip(approx, exact, table.output_ranges, strict=True):
            diff = np.abs(a - e[::step, ::step])
            cell = diff[:-1, :-1].reshape(n0, k, n1, k)[:, 1:, :, 1:]
            err = np.maximum(err, cell.max(axis=(1, 3)) / (hi - lo))
        worst.append(err)
    # the other diagonal only when it is better by more than rounding (of the reference too:
    # check grids may come from the compiled exact method), so that ties stay on the main one
    return (worst[1] < worst[0] - SPLIT_TIE).astype(np.uint8)


def _check_q15_full_scale(var: Variable, values: FloatArray) -> None:
    """Q15 stores outputs as fractions of max(|low|, |high|); Sugeno outputs can go beyond it."""
    scale = max(abs(var.low), abs(var.high))
    peak = float(np.max(np.abs(values)))
    if peak > scale:
        raise CodegenError(
            f"output {var.name} reaches {peak:.6g}, beyond the Q15 full scale {scale:.6g} "
            f"(the larger end of its range [{var.low:.6g}, {var.high:.6g}]); Sugeno outputs are "
            "not clamped to their range: widen the range or use --type float or double"
        )


def table_problem(rb: RuleBase, number_type: str) -> str | None:
    """Why ``rb`` cannot be made into a lookup table (None when it can)."""
    if number_type not in NUMBER_TYPES:
        return f"unknown number type {number_type!r} (expected one of {', '.join(NUMBER_TYPES)})"
    if not 1 <= len(rb.inputs) <= 3:
        return f"lookup tables support 1 to 3 inputs, got {len(rb.inputs)}"
    if not rb.outputs:
        return "has no outputs"
    if rb.out_of_range != "clamp":
        return (
            f"out_of_range is {rb.out_of_range!r}; a lookup table clamps its inputs, so only "
            "'clamp' can be compiled exactly"
        )
    for var in rb.inputs + rb.outputs:
        if not (math.isfinite(var.low) and math.isfinite(var.high) and var.low < var.high):
            return f"variable {var.name}: range [{var.low}, {var.high}] is not usable"
    return None


def _check_rule_base(rb: RuleBase, number_type: str) -> None:
    why = table_problem(rb, number_type)
    if why is None:
        return
    if why.startswith("unknown number type") or why.startswith("variable "):
        raise CodegenError(why)
    raise CodegenError(f"rule base {rb.name}: {why}")


def make_table(
    rb: RuleBase,
    *,
    number_type: NumberType = "float",
    tolerance: float | None = None,
    resolution: int | Sequence[int] | None = None,
    max_points: int = DEFAULT_MAX_POINTS,
    evaluate: Evaluator | None = None,
    progress: ProgressFn | None = None,
) -> LookupTable:
    """The smallest table found whose verified bound meets ``tolerance``, or one of ``resolution``.

    Parameters
    ----------
    rb
        A validated rule base with 1 to 3 inputs and the ``clamp`` out-of-range policy.
    number_type
        ``float``, ``double`` or ``q15``; the bound is measured for that type.
    tolerance
        Allowed error as a fraction of each output's range (default 1e-3). With
        ``resolution`` it is checked only when given explicitly (the size was chosen, the
        bound is reported).
    resolution
        Breakpoints per input (one number for all inputs, or one per input); when given, no
        search is made.
    max_points
        Cap on grid nodes for the search.
    evaluate
        The reference evaluator (default: the exact engine); for tests.
    progress
        Told the exact-engine points evaluated for each table tried (see
        :data:`ProgressFn`); the search may try several tables, each a new task.

    Raises
    ------
    CodegenError
        If the rule base cannot be tabulated, or the bound exceeds the tolerance (with
        ``resolution``) or cannot be brought under it within ``max_points``.
    """
    _check_rule_base(rb, number_type)
    tol = DEFAULT_TOLERANCE if tolerance is None else float(tolerance)
    if not (math.isfinite(tol) and tol > 0):
        raise CodegenError(f"tolerance must be a positive number, got {tolerance}")
    evaluator = evaluate if evaluate is not None else _default_evaluator(rb)
    if resolution is not None:
        counts = [resolution] * len(rb.inputs) if isinstance(resolution, int) else list(resolution)
        if len(counts) != len(rb.inputs) or any(
            not MIN_BREAKPOINTS <= int(c) <= MAX_BREAKPOINTS for c in counts
        ):
            raise CodegenError(
                f"resolution must give {len(rb.inputs)} count(s) between {MIN_BREAKPOINTS} "
                f"and {MAX_BREAKPOINTS}, got {resolution}"
            )
        check = check_points_for([int(c) for c in counts])
        if check > MAX_CHECK_POINTS:
            raise CodegenError(
                f"rule base {rb.name}: a {'x'.join(str(int(c)) for c in counts)} table needs "
                f"{check:,} check points to certify its bound (at most {MAX_CHECK_POINTS:,} "
                f"keep a compile under 1 GB); use fewer breakpoints per input or --method exact"
            )
        given = None if tolerance is None else tol
        table = build_table(
            rb,
            counts,
            number_type=number_type,
            tolerance=given,
            evaluate=evaluator,
            progress=progress,
        )
        if tolerance is not None:
            _enforce(table, f"resolution {resolution}")
        return table
    return _search(rb, number_type, tol, max_points, evaluator, progress)


def _enforce(table: LookupTable, what: str) -> None:
    bad = [
        f"{name}: bound {b:.3g} > tolerance {t:.3g}"
        for name, b, t in zip(table.output_names, table.bound, table.tolerance, strict=True)
        if b > t
    ]
    if bad:
        raise CodegenError(
            f"{what} ({'x'.join(map(str, table.shape))} table) does not meet the tolerance: "
            + "; ".join(bad)
            + " (use more breakpoints or a larger --tolerance)"
        )


def _search(
    rb: RuleBase,
    number_type: NumberType,
    tol: float,
    max_points: int,
    evaluator: Evaluator,
    progress: ProgressFn | None,
) -> LookupTable:
    # Interpolation error falls like h**2, so each miss predicts the spacing needed; nodes on
    # the knots make the error non-monotonic in h, hence the small downward sweep at the end.
    def counts_for(cells: int) -> list[int]:
        return [_axis_count_for_spacing(v, cells) for v in rb.inputs]

    def ratio(table: LookupTable) -> float:
        return max(b / t for b, t in zip(table.bound, table.tolerance, strict=True))

    cells = 4
    best: LookupTable | None = None
    last: LookupTable | None = None
    for _ in range(12):
        counts = counts_for(cells)
        if math.prod(counts) > max_points:
            break
        try:
            last = build_table(
                rb,
                counts,
                number_type=number_type,
                tolerance=tol,
                evaluate=evaluator,
                progress=progress,
            )
        except Q15ResolutionError as exc:
            # The search chose these breakpoints, not the user: say what cannot be done.
            detail = f"best tried: {last.describe()}; " if last is not None else ""
            raise CodegenError(
                f"the tolerance of {percent(tol)} of the output range cannot be met at Q15 "
                "resolution "
                f"({detail}input {exc.variable} would need {exc.count} breakpoints, closer "
                f"than the {exc.codes} Q15 codes of its range allow); raise --tolerance or "
                "use --type float"
            ) from None
        r = ratio(last)
        if r <= 1.0:
            best = last
            break
        grow = math.sqrt(r) * 1.05 if math.isfinite(r) else 2.0
        cells = max(cells + 1, math.ceil(cells * min(grow, 4.0)))
    if best is None:
        # Before saying it cannot be done, make sure: every resolution within the cap.
        best, top = _scan_uniform(rb, number_type, tol, max_points, evaluator, progress)
        if best is None:
            detail = f"; best tried: {last.describe()}" if last is not None else ""
            size = "x".join([str(top)] * len(rb.inputs))
            raise CodegenError(
                f"the tolerance of {percent(tol)} of the output range cannot be met within "
                f"{max_points} table points: no table of 2 to {top} breakpoints on every input "
                f"(up to {size}) meets it, each shown by its cell edges or built and "
                f"certified{detail}; raise --tolerance"
            )
        return best
    # Try a few smaller spacings below the first success.
    for smaller in range(cells - 1, max(cells - 4, 1), -1):
        counts = counts_for(smaller)
        if counts == list(best.shape):
            continue
        try:
            trial = build_table(
                rb,
                counts,
                number_type=number_type,
                tolerance=tol,
                evaluate=evaluator,
                progress=progress,
            )
        except Q15ResolutionError:  # pragma: no cover - fewer points than a success
            continue
        if ratio(trial) <= 1.0 and trial.n_points < best.n_points:
            best = trial
    return best


def _scan_uniform(
    rb: RuleBase,
    number_type: NumberType,
    tol: float,
    max_points: int,
    evaluator: Evaluator,
    progress: ProgressFn | None,
) -> tuple[LookupTable | None, int]:
    """A table of the same breakpoint count on every input that meets ``tol``, or None when
    no count within ``max_points`` (and the check-grid cap) does.

    A count is settled by its cell edges when they alone prove the bound too large
    (:func:`_edges_refute`, a few lines of check points), else by building and certifying
    its table. The largest count first: when it meets the tolerance, bisection finds a count
    that meets it with the next smaller one failing; when it does not, every other count is
    settled before None is returned. Returns the table and the largest count.
    """
    d = len(rb.inputs)
    top = MIN_BREAKPOINTS
    while (
        top < MAX_BREAKPOINTS
        and (top + 1) ** d <= max_points
        and check_points_for([top + 1] * d) <= MAX_CHECK_POINTS
    ):
        top += 1
    limit = tuple(tol * (v.high - v.low) for v in rb.outputs)
    hint = np.array([0.5 * (v.low + v.high) for v in rb.inputs])
    settled = [0]

    def settle(count: int) -> LookupTable | None:
        nonlocal hint
        if progress is not None:
            settled[0] += 1
            progress("resolutions", settled[0], top - MIN_BREAKPOINTS + 1)
        try:
            refuted, hint = _edges_refute(rb, [count] * d, number_type, limit, evaluator, hint)
            if refuted:
                return None
            table = build_table(
                rb, [count] * d, number_type=number_type, tolerance=tol, evaluate=evaluator,
                progress=progress,
            )  # fmt: skip
        except Q15ResolutionError:  # this many breakpoints do not fit Q15 codes
            return None
        ok = all(b <= t for b, t in zip(table.bound, table.tolerance, strict=True))
        return table if ok else None

    best = settle(top)
    if best is None:
        for count in range(MIN_BREAKPOINTS, top):
            found = settle(count)
            if found is not None:
                return found, top
        return None, top
    low, high = MIN_BREAKPOINTS - 1, top  # high meets the tolerance, low does not (or is 1)
    while high - low > 1:
        mid = (low + high) // 2
        found = settle(mid)
        if found is not None:
            high, best = mid, found
        else:
            low = mid
    return best, top


def _edges_refute(
    rb: RuleBase,
    counts: Sequence[int],
    number_type: NumberType,
    limit: Sequence[float],
    evaluator: Evaluator,
    hint: FloatArray,
) -> tuple[bool, FloatArray]:
    """Whether the cell edges of a ``counts`` table prove its bound above ``limit``.

    The surface is sampled on the check points of grid lines through the nodes
    (:mod:`fuzzkit.codegen.edge_floor`), nearest ``hint`` first: a few edges around it on the
    nearest lines, then whole lines, one, two, four, ...; it stops at the first output whose
    floor, less the rounding the table's arithmetic may add, times the bound's margin
    exceeds its limit. Returns the verdict and where the largest floor was found (the next
    count's ``hint``).
    """
    _, bps = _table_breakpoints(rb, counts, number_type)
    factor = check_factor_for([len(b) for b in bps])
    axes = _check_axes(bps, factor, number_type)
    span = np.array([v.high - v.low for v in rb.inputs])
    scale = np.array([max(abs(v.low), abs(v.high)) for v in rb.outputs])
    slack = scale * {"double": 2.0**-40, "float": 2.0**-20, "q15": 8.0 / Q15_ONE}[number_type]
    need = np.array(limit) / bound_margin(factor) + slack
    lines: list[tuple[float, int, tuple[int, ...]]] = []
    for a in range(len(bps)):
        others = [b for b in range(len(bps)) if b != a]
        for idx in itertools.product(*(range(len(bps[b])) for b in others)):
            far = sum(
                ((bps[b][i] - hint[b]) / span[b]) ** 2 for b, i in zip(others, idx, strict=True)
            )
            lines.append((float(far), a, idx))
    lines.sort(key=lambda line: line[0])
    worst, where = np.zeros(len(rb.outputs)), hint

    def sample(chosen: Sequence[tuple[float, int, tuple[int, ...]]], window: int | None) -> None:
        nonlocal where
        for a in range(len(bps)):
            group = [idx for _, ax, idx in chosen if ax == a]
            if not group:
                continue
            edges = len(bps[a]) - 1
            lo, hi = 0, edges
            if window is not None:
                at = int(np.clip(np.searchsorted(bps[a], hint[a]) - 1, 0, edges - 1))
                lo, hi = max(0, at - window), min(edges, at + window + 1)
            t = axes[a][lo * factor : hi * factor + 1]
            others = [b for b in range(len(bps)) if b != a]
            inputs = {}
            for b, var in enumerate(rb.inputs):
                if b == a:
                    inputs[var.name] = np.tile(t, len(group))
                else:
                    col = np.array([bps[b][idx[others.index(b)]] for idx in group])
                    inputs[var.name] = np.repeat(col, len(t))
            got = evaluator(inputs)
            for k, var in enumerate(rb.outputs):
                f = np.asarray(got[var.name], dtype=np.float64).reshape(len(group), len(t))
                floor, pos = chord_floor(t, f, factor)
                line = int(np.argmax(floor))
                if floor[line] > worst[k]:
                    worst[k] = floor[line]
                    where = np.array([inputs[v.name][line * len(t) + pos[line]] for v in rb.inputs])

    sample(lines[:4], 4)
    if np.any(worst > need):
        return True, where
    start, size = 0, 1
    while start < len(lines):
        sample(lines[start : start + size], None)
        if np.any(worst > need):
            return True, where
        start, size = start + size, 2 * size
    return False, where
