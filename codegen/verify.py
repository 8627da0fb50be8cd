"""Equivalence check: generated code against the exact engine (``--verify``, tests).

Random points over the input ranges plus every combination of edge values (range ends, just
beyond, far beyond, +-huge, +-inf, NaN) are evaluated by the generated code and by the exact
engine; every finite difference must stay within the table's published bound plus a stated
rounding allowance, and NaN must appear exactly where the engine gives NaN.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
import sys
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.codegen.budget import VERIFY_SECONDS, EngineBudget
from fuzzkit.codegen.lookup_table import Q15_ONE, ROUNDING_ALLOWANCE, LookupTable, quantize_q15
from fuzzkit.codegen.names import symbol
from fuzzkit.codegen.progress import ProgressFn
from fuzzkit.codegen.toolchain import CompiledTable
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import RuleBase, Variable

FloatArray = npt.NDArray[np.float64]

#: Rounding allowance on top of the bound, as a fraction of each output's full scale (see
#: ``lookup_table.ROUNDING_ALLOWANCE``: the bound models float32 and Q15 arithmetic operation for
#: operation, so only FMA contraction and double rounding are left; none for Q15).
ROUNDING = ROUNDING_ALLOWANCE
DEFAULT_POINTS = 100_000
#: Points per call when a verification reports progress: a pure-Python module takes about
#: 150 us a point, so a chunk is about 0.3 s (progress, and a Ctrl-C, every chunk).
PROGRESS_CHUNK = 2048


@dataclass(frozen=True)
class Verification:
    """Outcome of one equivalence check."""

    target: str
    n_points: int
    max_error: tuple[float, ...]
    bound: tuple[float, ...]
    allowance: tuple[float, ...]
    nan_mismatches: int
    #: Exact method, discontinuous defuzzifiers: points that jumped to another maximum at a
    #: near-tie (ok while under 1 % of the points; see compare_exact).
    tie_jumps: int = 0

    @property
    def ok(self) -> bool:
        """True when every error is within bound + allowance and NaN matched everywhere."""
        return (
            self.nan_mismatches == 0
            and 100 * self.tie_jumps <= self.n_points
            and all(
                e <= b + a
                for e, b, a in zip(self.max_error, self.bound, self.allowance, strict=True)
            )
        )

    def describe(self) -> str:
        """One line for humans."""
        parts = ", ".join(
            f"max error {e:.3g} <= {b:.3g} + {a:.2g}"
            if e <= b + a
            else f"max error {e:.3g} EXCEEDS {b:.3g} + {a:.2g}"
            for e, b, a in zip(self.max_error, self.bound, self.allowance, strict=True)
        )
        nan = "" if not self.nan_mismatches else f", {self.nan_mismatches} NaN mismatches"
        if self.tie_jumps:
            nan += f", {self.tie_jumps} jumps at near-ties of two maxima"
        verdict = "ok" if self.ok else "FAILED"
        return f"verify {self.target}: {verdict} on {self.n_points} points ({parts}{nan})"


def edge_values(low: float, high: float) -> list[float]:
    """Values that stress one input: ends, just beyond, far beyond, huge, inf, NaN."""
    span = high - low
    return [
        low,
        high,
        0.5 * (low + high),
        low - 1e-9 * span,
        high + 1e-9 * span,
        low - span,
        high + span,
        -1e30,
        1e30,
        -math.inf,
        math.inf,
        math.nan,
    ]


def weak_values(var: Variable, count: int = 3) -> list[float]:
    """Where ``var``'s strongest term is weakest (but not 0), ``count`` values of its range.

    Between Gaussian terms of small sigma every membership can be 1e-20 and less; there an
    implementation that loses the firing levels' scale (the point where an edge meets a tiny
    level is the edge's foot to the last bit) still gets a plausible number. These values
    make the verification look there.
    """
    x = np.linspace(var.low, var.high, 2049)
    strongest = np.max([membership.evaluate_term(t, x) for t in var.terms], axis=0)
    order = [int(i) for i in np.argsort(np.where(strongest > 0, strongest, np.inf))]
    picked: list[int] = []
    for i in order:  # the weakest, each at least 1 % of the range from the others
        if strongest[i] > 0 and all(abs(i - j) > 20 for j in picked):
            picked.append(i)
        if len(picked) == count:
            break
    return [float(x[i]) for i in picked]


def verification_points(rb: RuleBase, n: int = DEFAULT_POINTS, seed: int = 0) -> FloatArray:
    """``n`` seeded random points in range, every combination of edge values, and of the
    inputs' :func:`weak_values` (with each range's middle)."""
    rng = np.random.default_rng(seed)
    rand = np.column_stack([rng.uniform(v.low, v.high, n) for v in rb.inputs])
    edges = np.array(
        list(itertools.product(*[edge_values(v.low, v.high) for v in rb.inputs])),
        dtype=np.float64,
    )
    weak = np.array(
        list(itertools.product(*[[*weak_values(v), 0.5 * (v.low + v.high)] for v in rb.inputs])),
        dtype=np.float64,
    )
    return np.vstack([rand, edges, weak])


def _exact(rb: RuleBase, points: FloatArray, meter: _Meter | None = None) -> FloatArray:
    from fuzzkit.fuzzy.inference import Engine

    engine = Engine(rb)
    # refused before any work if the engine would take too long (codegen.budget)
    EngineBudget(engine, "--verify", VERIFY_SECONDS).charge(points.shape[0])

    def run(part: FloatArray) -> FloatArray:
        result = engine.evaluate({v.name: part[:, i] for i, v in enumerate(rb.inputs)})
        return np.column_stack([np.asarray(result[v.name], dtype=np.float64) for v in rb.outputs])

    return run(points) if meter is None else meter.map(run, points)


class _Meter:
    """Evaluates in chunks of :data:`PROGRESS_CHUNK` points and reports each to ``progress``
    (``task``: what is verified; ``total``: every point of every evaluator the check runs).
    Each point is evaluated on its own, so chunking changes no value."""

    def __init__(self, progress: ProgressFn, task: str, total: int) -> None:
        self.progress = progress
        self.task = task
        self.total = total
        self.done = 0

    def map(
        self, fn: Callable[[npt.NDArray[Any]], npt.NDArray[Any]], points: npt.NDArray[Any]
    ) -> npt.NDArray[Any]:
        parts = []
        self.progress(self.task, self.done, self.total)
        for start in range(0, points.shape[0], PROGRESS_CHUNK):
            part = points[start : start + PROGRESS_CHUNK]
            parts.append(fn(part))
            self.done += part.shape[0]
            self.progress(self.task, self.done, self.total)
        return np.vstack(parts)


def _meter(progress: ProgressFn | None, task: str, points: npt.NDArray[Any]) -> _Meter | None:
    """A meter over the generated code's and the engine's evaluation of ``points``."""
    return None if progress is None else _Meter(progress, f"verify {task}", 2 * points.shape[0])


def _generated(
    evaluate: Callable[[npt.NDArray[Any]], npt.NDArray[Any]],
    points: npt.NDArray[Any],
    meter: _Meter | None,
) -> npt.NDArray[Any]:
    return evaluate(points) if meter is None else meter.map(evaluate, points)


def compare(
    rb: RuleBase, table: LookupTable, target: str, got: FloatArray, exact: FloatArray
) -> Verification:
    """Compare generated outputs ``got`` with ``exact`` (both ``(n, n_outputs)``)."""
    nan_got = np.isnan(got)
    nan_exact = np.isnan(exact)
    mismatches = int(np.count_nonzero(nan_got != nan_exact))
    both = ~nan_got & ~nan_exact
    errors = []
    for k in range(got.shape[1]):
        col = both[:, k]
        diff = np.abs(got[col, k] - exact[col, k])
        errors.append(float(diff.max()) if diff.size else 0.0)
    rounding = ROUNDING[table.number_type]
    allowance = tuple(rounding * max(abs(v.low), abs(v.high)) for v in rb.outputs)
    return Verification(
        target=target,
        n_points=int(got.shape[0]),
        max_error=tuple(errors),
        bound=table.bound,
        allowance=allowance,
        nan_mismatches=mismatches,
    )


def c_points(table: LookupTable, points: FloatArray) -> tuple[npt.NDArray[Any], FloatArray]:
    """The points as the C API takes them, and the same points as real values for the engine.

    float: cast to float32 (the engine sees the cast value). q15: quantised to codes (NaN and
    infinities have no code and are dropped; +-huge saturate).
    """
    if table.number_type == "q15":
        layout = table.q15
        if layout is None:  # pragma: no cover - a q15 table always has a layout
            raise CodegenError("internal: q15 table without layout")
        finite = np.all(np.isfinite(points), axis=1)
        pts = points[finite]
        codes = np.column_stack([quantize_q15(pts[:, i], s) for i, s in enumerate(layout.in_scale)])
        real = codes.astype(np.float64) * (np.array(layout.in_scale) / Q15_ONE)
        return codes.astype(np.int16), real
    dtype = np.float32 if table.number_type == "float" else np.float64
    with np.errstate(over="ignore"):
        cast = points.astype(dtype)
    return cast, cast.astype(np.float64)


def c_outputs_real(table: LookupTable, raw: npt.NDArray[Any]) -> FloatArray:
    """C outputs in real units (Q15 codes scaled by each output's full scale)."""
    if table.q15 is not None:
        return raw.astype(np.float64) * (np.array(table.q15.out_scale) / Q15_ONE)
    return raw.astype(np.float64)


def verify_c(
    rb: RuleBase,
    table: LookupTable,
    files: Mapping[str, str],
    *,
    n: int = DEFAULT_POINTS,
    compiler: Sequence[str] | None = None,
    progress: ProgressFn | None = None,
) -> Verification:
    """Compile ``files`` (strict flags), load them and compare with the exact engine."""
    points = verification_points(rb, n)
    args, real = c_points(table, points)
    meter = _meter(progress, f"c ({table.number_type})", real)
    fpi = len(rb.inputs) == 2
    with CompiledTable(
        files,
        symbol(rb.name),
        table.number_type,
        len(rb.inputs),
        len(rb.outputs),
        fpi=fpi,
        compiler=compiler,
    ) as lib:
        got = c_outputs_real(table, _generated(lib.eval_batch, args, meter))
    return compare(rb, table, f"c ({table.number_type})", got, _exact(rb, real, meter))


def load_module(files: Mapping[str, str], name: str) -> ModuleType:
    """Import the generated Python module from a temporary folder (without touching sys.path)."""
    with tempfile.TemporaryDirectory(prefix="fuzzkit-py-") as tmp:
        path = Path(tmp) / f"{name}.py"
        path.write_text(files[f"{name}.py"], encoding="utf-8")
        spec = importlib.util.spec_from_file_location(f"fuzzkit_generated_{name}", path)
        if spec is None or spec.loader is None:  # pragma: no cover
            raise CodegenError(f"cannot import generated module {path}")
        module = importlib.util.module_from_spec(spec)
        # Register while executing so dataclass-like introspection works, then drop it.
        sys.modules[spec.name] = module
        try:
            spec.loader.exec_module(module)
        finally:
            sys.modules.pop(spec.name, None)
    return module


def python_outputs(
    evaluate: Callable[[Sequence[float]], tuple[float, ...]], points: FloatArray
) -> FloatArray:
    """Call a generated ``eval`` on every row."""
    return np.array([evaluate(tuple(row)) for row in points.tolist()], dtype=np.float64)


def verify_python(
    rb: RuleBase,
    table: LookupTable,
    files: Mapping[str, str],
    *,
    n: int = DEFAULT_POINTS,
    progress: ProgressFn | None = None,
) -> Verification:
    """Import the generated module and compare its ``eval`` with the exact engine."""
    module = load_module(files, symbol(rb.name))
    points = verification_points(rb, n)
    meter = _meter(progress, "python", points)
    got = _generated(lambda p: python_outputs(module.eval, p), points, meter)
    return compare(rb, table, "python", got, _exact(rb, points, meter))


def compare_exact(
    rb: RuleBase, number_type: str, target: str, got: FloatArray, exact: FloatArray
) -> Verification:
    """Compare exact-method outputs with the engine: rounding only (``exact.ROUNDING_BOUND``,
    of the output's full scale, or of the value where that is larger).

    For mean/smallest/largest of maximum a point where two maxima tie to within rounding can
    jump to the other maximum; such points are counted in ``tie_jumps`` rather than in the
    error, and the check passes while they stay below 1 % of the points (double: the engine's
    own tie tolerance, 1e-10 of the height, makes them rare; float rounds levels to 1e-7, so
    nearly flat or nearly tied maxima, e.g. under probabilistic-sum aggregation, jump more
    often).
    """
    from fuzzkit.codegen.exact import DISCONTINUOUS, rounding_allowance

    allowance = rounding_allowance(rb, number_type)
    nan_got = np.isnan(got)
    nan_exact = np.isnan(exact)
    mismatches = int(np.count_nonzero(nan_got != nan_exact))
    both = ~nan_got & ~nan_exact
    errors = []
    jumps = 0
    for k in range(got.shape[1]):
        want = exact[both[:, k], k]
        have = got[both[:, k], k]
        if number_type == "float":
            # a value beyond float's range (a linear Sugeno term at a huge input) rounds to
            # +-inf: that is the float nearest to it, and nothing else is
            with np.errstate(over="ignore"):
                beyond = np.isinf(want.astype(np.float32)) & np.isfinite(want)
            wrong = np.any(have[beyond] != np.copysign(np.inf, want[beyond]))
            want, have = want[~beyond], have[~beyond]
            if wrong:
                errors.append(math.inf)
                continue
        # rounding is relative to the output's full scale, or to the value where it is larger
        # (a Sugeno output is not held to its range: 1e100 inputs under `extend`)
        scale = np.maximum(1.0, np.abs(want) / max(abs(rb.outputs[k].low), abs(rb.outputs[k].high)))
        diff = np.abs(have - want) / scale
        if rb.defuzzifier in DISCONTINUOUS:
            over = diff > allowance[k]
            jumps += int(np.count_nonzero(over))
            diff = diff[~over]
        errors.append(float(diff.max()) if diff.size else 0.0)
    return Verification(
        target=target,
        n_points=int(got.shape[0]),
        max_error=tuple(errors),
        bound=tuple(0.0 for _ in errors),
        allowance=allowance,
        nan_mismatches=mismatches,
        tie_jumps=jumps,
    )


def verify_exact_c(
    rb: RuleBase,
    number_type: str,
    files: Mapping[str, str],
    *,
    n: int = DEFAULT_POINTS,
    compiler: Sequence[str] | None = None,
    flags: Sequence[str] | None = None,
    progress: ProgressFn | None = None,
) -> Verification:
    """Compile exact-method C, load it and compare with the exact engine."""
    points = verification_points(rb, n)
    dtype = np.float32 if number_type == "float" else np.float64
    with np.errstate(over="ignore"):
        args = points.astype(dtype)
    meter = _meter(progress, f"c exact ({number_type})", points)
    extra = {} if flags is None else {"flags": tuple(flags)}
    with CompiledTable(
        files,
        symbol(rb.name),
        number_type,
        len(rb.inputs),
        len(rb.outputs),
        fpi=len(rb.inputs) == 2,
        compiler=compiler,
        **extra,
    ) as lib:
        got = _generated(lib.eval_batch, args, meter).astype(np.float64)
    real = args.astype(np.float64)
    return compare_exact(rb, number_type, f"c exact ({number_type})", got, _exact(rb, real, meter))


def verify_exact_python(
    rb: RuleBase,
    files: Mapping[str, str],
    *,
    n: int = DEFAULT_POINTS,
    progress: ProgressFn | None = None,
) -> Verification:
    """Import exact-method Python and compare its ``eval`` with the exact engine."""
    module = load_module(files, symbol(rb.name))
    points = verification_points(rb, n)
    meter = _meter(progress, "python exact", points)
    got = _generated(lambda p: python_outputs(module.eval, p), points, meter)
    return compare_exact(rb, "double", "python exact", got, _exact(rb, points, meter))
