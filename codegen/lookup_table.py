"""Lookup tables: sample the exact engine on a grid and certify the interpolation error.

A :class:`LookupTable` holds, for a rule base with 1 to 3 inputs, the breakpoints of every input
axis and the sampled value of every output at every grid node. Between nodes the table is read
by multilinear interpolation, with each input first clamped to its range (the engine's default
``clamp`` policy, so clamping is exact, not an approximation).

Breakpoints are placed on the *knots* of the input terms (the vertices of piecewise-linear
membership functions: where the surface has kinks), an even number per knot interval (so the
midpoints, where neighbouring labels cross at 0.5, are nodes too), crowded symmetrically
towards the knots where the surface curves most (see ``_grade``).

Two-input tables are read linearly on the two triangles of each cell, cut along the diagonal
that fits the surface better (chosen per cell): AND = min makes creases along exactly such
diagonals, where a bilinear patch converges only like the cell width.

The bound is *measured*, not derived: the error against the exact engine is evaluated on a check
grid at least ``CHECK_FACTOR`` (4) times denser than the table along every axis (8 for two
inputs, 16 for one; so it contains every cell centre, every edge midpoint and the quarter
points), with the values as stored in the target number type and, for Q15, with a bit-exact
model of the generated integer arithmetic. It is a measured maximum, not a proof: between check
points the error can exceed it slightly, which the tests quantify on random points.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import CodegenError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
NumberType = Literal["float", "double", "q15"]
#: Evaluates a rule base on broadcastable arrays, ``{input: array} -> {output: array}``.
Evaluator = Callable[[Mapping[str, FloatArray]], Mapping[str, FloatArray]]

NUMBER_TYPES: tuple[NumberType, ...] = ("float", "double", "q15")


def percent(fraction: float) -> str:
    """A share of an output's range as people write it: ``0.001`` -> ``0.1 %``."""
    return f"{100.0 * fraction:.3g} %"


#: Default tolerance, as a fraction of each output's range.
DEFAULT_TOLERANCE = 1e-3
#: The check grid has this many sub-intervals per table cell and axis (>= 4 by contract).
CHECK_FACTOR = 4
#: The published bound is the check-grid maximum times this: between check points the error
#: can exceed the sampled maximum a little (0.3% was seen on 1e5 random points of a 13x13
#: MacVicar-Whelan table); the tests hold every target to the published bound.
BOUND_MARGIN = 1.05
#: The margin when only a 4x check grid was affordable (large 3-input tables): 10% over the
#: 4x maximum was seen on random points of a 9x9x9 table.
COARSE_BOUND_MARGIN = 1.2


def bound_margin(check_factor: int) -> float:
    """The factor the check-grid maximum is multiplied by for a grid ``check_factor`` x denser."""
    return BOUND_MARGIN if check_factor >= 8 else COARSE_BOUND_MARGIN


#: What verification allows on top of the bound, as a fraction of each output's full scale
#: (largest |range end|). The bound already models the stored values and, for float, the
#: float32 breakpoints, constants and arithmetic of the generated C operation for operation
#: (Q15: bit for bit), so this covers only what a model cannot know: a compiler fusing
#: ``a + t * d`` into one FMA rounds once instead of twice (a few ulp of the output).
ROUNDING_ALLOWANCE: dict[str, float] = {"float": 2.0**-20, "double": 2.0**-48, "q15": 0.0}
#: Two inputs: cells whose check-grid error is at least this share of the maximum are
#: sampled again REFINE_FACTOR x per axis (at most REFINE_CELLS of them, worst first): see
#: _refine_worst_cells.
REFINE_SHARE = 0.85
REFINE_FACTOR = 64
REFINE_CELLS = 64
#: Exponent of the node grading between knots (see _grade).
GRADING = 1.5
#: Largest table (grid nodes, all axes multiplied) the tolerance search may produce.
DEFAULT_MAX_POINTS = 65536
#: Fewest and most breakpoints per axis.
MIN_BREAKPOINTS = 2
MAX_BREAKPOINTS = 4096
#: Q15: one unit of the last place is 1/32768 of a variable's full scale.
Q15_ONE = 32768
#: Q15 interpolation fraction: t in [0, 2**Q15_T_BITS] (Q14 keeps every product inside int32).
Q15_T_BITS = 14
#: Q15 reciprocal cell widths are scaled by 2**Q15_RECIP_BITS (t = (dq * recip) >> 16).
Q15_RECIP_BITS = 30


class Q15ResolutionError(CodegenError):
    """Breakpoints closer than one Q15 code (two would round to the same code)."""

    def __init__(self, message: str, variable: str, count: int, codes: int) -> None:
        super().__init__(message)
        self.variable = variable
        self.count = count
        self.codes = codes


@dataclass(frozen=True, eq=False)
class Q15Layout:
    """How a Q15 table maps integers to values: ``value = q * full_scale / 32768``.

    ``in_scale``/``out_scale`` are the full scales (the largest magnitude of each variable's
    range, so 0 is exact and the whole range fits); ``q_breakpoints`` are the breakpoints in
    Q15 units, ``q_low``/``q_high`` the clamping limits of each input, and ``recip`` the
    reciprocal cell widths ``round(2**30 / width)`` the generated code multiplies by instead
    of dividing.
    """

    in_scale: tuple[float, ...]
    out_scale: tuple[float, ...]
    q_low: tuple[int, ...]
    q_high: tuple[int, ...]
    q_breakpoints: tuple[IntArray, ...]
    recip: tuple[IntArray, ...]


def _fixed(x: float, scale: float, lo: int, hi: int) -> int:
    """``round(x * scale)`` (half away from zero) saturated to ``[lo, hi]``; NaN -> 0."""
    v = x * scale
    if math.isnan(v):
        return 0
    if v >= hi:
        return hi
    if v <= lo:
        return lo
    return math.floor(abs(v) + 0.5) * (1 if v >= 0 else -1)


def q15_fpi_codes(
    layout: Q15Layout, kp: float, ki: float, kx: float, u_min: float, u_max: float
) -> tuple[int, int, int, int, int]:
    """The Q15 fuzzy-PI's gain and limit codes ``NAME_fpi_init`` takes (its header's formulas).

    Gains are rounded to float32 first (as a float gains file states them), then
    ``KP = round(kp / IN1_FULL_SCALE * 65536)``, ``KI = round(ki / IN0_FULL_SCALE * 65536)``,
    ``KX = round(kx * OUT0_FULL_SCALE * 65536)`` saturated to int32, and the limits
    ``round(u * 32768)`` saturated to int16. Done here, at generation time, so the generated
    Q15 code holds no floating point at all.
    """
    big = 2**31 - 1
    f32 = [float(np.float32(g)) for g in (kp, ki, kx, u_min, u_max)]
    return (
        _fixed(f32[0] / layout.in_scale[1], 65536.0, -big, big),
        _fixed(f32[1] / layout.in_scale[0], 65536.0, -big, big),
        _fixed(f32[2] * layout.out_scale[0], 65536.0, -big, big),
        _fixed(f32[3], 32768.0, -32768, 32767),
        _fixed(f32[4], 32768.0, -32768, 32767),
    )


@dataclass(frozen=True, eq=False)
class LookupTable:
    """A rule base sampled on a grid, with the verified error bound of its interpolation.

    ``values[k]`` is the exact engine's output ``k`` at the grid nodes (float64, shape = number
    of breakpoints per input, first input slowest); ``stored[k]`` the node values the generated
    code uses, as the target number type keeps them (float32, float64 or int16 Q15 codes):
    the samples, or when ``fitted`` least-squares values with the knot-lattice nodes kept
    exact (see ``_fit_values``). ``measured[k]`` is the largest
    absolute error (output units) on the check grid for ``number_type`` (``check_factor`` x
    denser than the table per axis; 0 when unknown), ``bound[k]`` that times
    :func:`bound_margin` rounded up to 3 significant digits (the published, verified bound), and
    ``tolerance[k]`` the absolute tolerance it was held to (empty when none was: a table of
    a given resolution). For two inputs, ``splits[i, j]``
    says along which diagonal cell ``(i, j)`` is cut into two linear triangles (see
    :func:`_combine`); ``None`` otherwise.
    """

    rule_base_name: str
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    input_ranges: tuple[tuple[float, float], ...]
    output_ranges: tuple[tuple[float, float], ...]
    breakpoints: tuple[FloatArray, ...]
    values: tuple[FloatArray, ...]
    stored: tuple[npt.NDArray[np.generic], ...]
    number_type: NumberType
    q15: Q15Layout | None
    bound: tuple[float, ...]
    tolerance: tuple[float, ...]
    check_points: int
    measured: tuple[float, ...] = ()
    splits: npt.NDArray[np.uint8] | None = None
    fitted: bool = False
    check_factor: int = 0

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of breakpoints per input."""
        return tuple(len(b) for b in self.breakpoints)

    @property
    def n_points(self) -> int:
        """Grid nodes per output."""
        return math.prod(self.shape)

    @property
    def value_bytes(self) -> int:
        """Bytes of one stored value."""
        return {"float": 4, "double": 8, "q15": 2}[self.number_type]

    @property
    def memory_bytes(self) -> int:
        """Bytes of constant data the generated C keeps (tables, breakpoints, reciprocals)."""
        total = self.n_points * len(self.values) * self.value_bytes
        for axis, bp in enumerate(self.breakpoints):
            if self.q15 is not None:
                total += 2 * len(bp) + 4 * (len(bp) - 1)
            elif not self.is_uniform(axis):
                total += self.value_bytes * (2 * len(bp) - 1)  # breakpoints and 1/widths
            if self.q15 is not None or not self.is_uniform(axis):
                cells = self.index_map(axis)[0]
                total += cells.size * (1 if len(bp) <= 257 else 2)
        if self.splits is not None:
            total += (self.splits.size + 7) // 8
        return total

    def index_map(self, axis: int) -> tuple[IntArray, float]:
        """A first guess of the cell for a non-uniform axis, to replace a search in C.

        Returns ``(cells, scale)``. float/double: ``bin = int((x - low) * scale)`` (capped at
        the last bin), bins at most half the narrowest cell wide, so the cell is
        ``cells[bin]`` or a neighbour even when rounding puts ``x`` in the adjacent bin (the C
        then checks one breakpoint each way). Q15: ``bin = (q - q_low) >> scale``, bins of
        2**scale codes, no wider than the narrowest cell, so the cell is ``cells[bin]`` or the
        next one (exact integer arithmetic: one check).
        """
        if self.q15 is not None:
            qb = self.q15.q_breakpoints[axis]
            shift = int(np.min(np.diff(qb))).bit_length() - 1
            starts = np.arange(self.q15.q_low[axis], self.q15.q_high[axis] + 1, 1 << shift)
            cells = np.clip(np.searchsorted(qb, starts, side="right") - 1, 0, len(qb) - 2)
            return cells.astype(np.int64), float(shift)
        bp = self.breakpoints[axis]
        n_bins = 2 * math.ceil((bp[-1] - bp[0]) / float(np.min(np.diff(bp))))
        starts = bp[0] + (bp[-1] - bp[0]) * np.arange(n_bins) / n_bins
        cells = np.clip(np.searchsorted(bp, starts, side="right") - 1, 0, len(bp) - 2)
        return cells.astype(np.int64), n_bins / float(bp[-1] - bp[0])

    def is_uniform(self, axis: int) -> bool:
        """True when the breakpoints of ``axis`` are evenly spaced (indexed without a search)."""
        return _is_uniform(self.breakpoints[axis])

    def bound_summary(self) -> str:
        """Each output's verified bound and tolerance, absolute and as a share of its range:
        ``du: 0.00186 = 0.093 % of range (tolerance 0.002 = 0.1 %)``. The generated files'
        headers and ``fuzzkit compile`` print this same text."""
        parts = []
        ranges = self.output_ranges
        for k, (name, b, (lo, hi)) in enumerate(
            zip(self.output_names, self.bound, ranges, strict=True)
        ):
            text = f"{name}: {b:.3g} = {percent(b / (hi - lo))} of range"
            if self.tolerance:
                tol = self.tolerance[k]
                text += f" (tolerance {tol:.3g} = {percent(tol / (hi - lo))})"
            parts.append(text)
        return ", ".join(parts)

    def describe(self) -> str:
        """One line for humans: grid, memory and the bound relative to each output range."""
        grid = "x".join(str(n) for n in self.shape)
        return (
            f"table {grid} ({self.n_points} points, {self.memory_bytes} bytes, "
            f"{self.number_type}), verified bound {self.bound_summary()}"
        )

    def interpolate(self, inputs: Sequence[npt.ArrayLike]) -> tuple[FloatArray, ...]:
        """Reference evaluation in Python, as the generated code computes it.

        Inputs are values in input units (broadcast together). For ``double`` the
        interpolation runs in float64 over the stored values; for ``float`` the inputs are
        rounded to float32 and the generated C's float32 clamp, cell location and
        interpolation are reproduced operation for operation; for ``q15`` the inputs are first
        quantised to Q15 codes and the integer arithmetic of the generated C is reproduced
        bit for bit. NaN inputs give NaN.
        """
        return self.interpolate_with(inputs, self.splits)

    def interpolate_with(
        self, inputs: Sequence[npt.ArrayLike], splits: npt.NDArray[np.uint8] | None
    ) -> tuple[FloatArray, ...]:
        """:meth:`interpolate` with another choice of 2-D cell diagonals (for the builder)."""
        arrays = np.broadcast_arrays(*[np.asarray(x, dtype=np.float64) for x in inputs])
        if len(arrays) != len(self.breakpoints):
            raise CodegenError(f"expected {len(self.breakpoints)} inputs, got {len(arrays)}")
        nan = np.zeros(arrays[0].shape, dtype=bool)
        for x in arrays:
            nan |= np.isnan(x)
        if self.q15 is not None:
            codes = [quantize_q15(x, s) for x, s in zip(arrays, self.q15.in_scale, strict=True)]
            outs = self._q15(codes, splits)
            result = tuple(
                np.asarray(o, dtype=np.float64) * (s / Q15_ONE)
                for o, s in zip(outs, self.q15.out_scale, strict=True)
            )
        elif self.number_type == "float":
            idx32, frac32 = self._locate_float32(arrays)
            result = tuple(
                np.asarray(
                    _combine(np.asarray(tab, dtype=np.float32), idx32, frac32, splits, None),
                    dtype=np.float64,
                )
                for tab in self.stored
            )
        else:
            idx, frac = _locate_float(self.breakpoints, arrays)
            result = tuple(
                _combine(np.asarray(tab, dtype=np.float64), idx, frac, splits, None)
                for tab in self.stored
            )
        # Arrays even for scalar inputs (0-d), so NaN can be set and the type holds.
        result = tuple(np.array(r, dtype=np.float64) for r in result)
        for r in result:
            r[nan] = np.nan
        return result

    def float_constants(self, axis: int) -> tuple[float, float, float, FloatArray]:
        """``(low, high, 1 / step, 1 / widths)`` of an axis as the generated code holds them.

        The generated C rounds each to its number type; for ``float`` these values are
        rounded to float32 here too, so the model in :meth:`interpolate` uses the very
        constants the C does. ``1 / step`` is for uniform axes, ``1 / widths`` for the others.
        """
        bp = self.breakpoints[axis]
        inv_step = (len(bp) - 1) / (float(bp[-1]) - float(bp[0]))
        inv_widths: FloatArray = 1.0 / np.diff(bp)
        low, high = float(bp[0]), float(bp[-1])
        if self.number_type == "float":
            low, high, inv_step = (float(np.float32(v)) for v in (low, high, inv_step))
            inv_widths = inv_widths.astype(np.float32).astype(np.float64)
        return low, high, inv_step, inv_widths

    def _locate_float32(
        self, xs: Sequence[FloatArray]
    ) -> tuple[list[IntArray], list[npt.NDArray[np.float32]]]:
        """Cell and fraction as the generated float C computes them, in float32 throughout."""
        idx: list[IntArray] = []
        frac: list[npt.NDArray[np.float32]] = []
        for axis, x in enumerate(xs):
            bp = self.breakpoints[axis]
            n_cells = len(bp) - 1
            low, high, inv_step, inv_widths = (
                np.float32(v) if np.ndim(v) == 0 else np.asarray(v, dtype=np.float32)
                for v in self.float_constants(axis)
            )
            with np.errstate(over="ignore", invalid="ignore"):
                x32 = np.nan_to_num(x, nan=float(bp[0])).astype(np.float32)
            x32 = np.where(x32 < low, low, np.where(x32 > high, high, x32)).astype(np.float32)
            if self.is_uniform(axis):
                f = ((x32 - low) * inv_step).astype(np.float32)
                i = np.minimum(f.astype(np.int64), n_cells - 1)
                f = (f - i.astype(np.float32)).astype(np.float32)
            else:
                bp32 = bp.astype(np.float32)
                i = np.clip(np.searchsorted(bp32, x32, side="right") - 1, 0, n_cells - 1)
                f = ((x32 - bp32[i]) * np.asarray(inv_widths)[i]).astype(np.float32)
            idx.append(i.astype(np.int64))
            frac.append(np.minimum(f, np.float32(1.0)))
        return idx, frac

    def interpolate_q15(self, codes: Sequence[npt.ArrayLike]) -> tuple[IntArray, ...]:
        """Bit-exact model of the generated Q15 ``eval``: Q15 input codes in, codes out."""
        return self._q15([np.asarray(c, dtype=np.int64) for c in codes], self.splits)

    def _q15(
        self, codes: Sequence[IntArray], splits: npt.NDArray[np.uint8] | None
    ) -> tuple[IntArray, ...]:
        layout = self.q15
        if layout is None:
            raise CodegenError("Q15 evaluation needs a q15 table")
        idx: list[IntArray] = []
        frac: list[IntArray] = []
        for axis, q in enumerate(codes):
            qb = layout.q_breakpoints[axis]
            qc = np.clip(q, layout.q_low[axis], layout.q_high[axis])
            i = np.clip(np.searchsorted(qb, qc, side="right") - 1, 0, len(qb) - 2)
            t = ((qc - qb[i]) * layout.recip[axis][i]) >> (Q15_RECIP_BITS - Q15_T_BITS)
            idx.append(i)
            frac.append(np.minimum(t, 1 << Q15_T_BITS))
        return tuple(
            _combine(np.asarray(tab, dtype=np.int64), idx, frac, splits, Q15_T_BITS)
            for tab in self.stored
        )


def quantize_q15(x: npt.ArrayLike, scale: float) -> IntArray:
    """Q15 code of ``x`` for full scale ``scale``: round-to-nearest, saturated; NaN -> 0."""
    arr = np.asarray(x, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        scaled = np.clip(np.nan_to_num(arr, nan=0.0) * (Q15_ONE / scale), -32768.0, 32767.0)
    return np.rint(scaled).astype(np.int64)


def _is_uniform(bp: FloatArray) -> bool:
    steps = np.diff(bp)
    return bool(np.all(np.abs(steps - steps[0]) <= 1e-9 * (bp[-1] - bp[0])))


def _locate_float(
    breakpoints: Sequence[FloatArray], xs: Sequence[FloatArray]
) -> tuple[list[IntArray], list[FloatArray]]:
    """Cell index and fraction in [0, 1] of clamped inputs (NaN treated as the low end)."""
    idx: list[IntArray] = []
    frac: list[FloatArray] = []
    for bp, x in zip(breakpoints, xs, strict=True):
        xc = np.clip(np.nan_to_num(x, nan=bp[0]), bp[0], bp[-1])
        i = np.clip(np.searchsorted(bp, xc, side="right") - 1, 0, len(bp) - 2)
        idx.append(i)
        frac.append((xc - bp[i]) / (bp[i + 1] - bp[i]))
    return idx, frac


def _lerp_term(t: Any, d: Any, shift: int | None) -> Any:
    """``t * d`` in float, or ``round(t * d / 2**shift)`` with a floor shift in Q15."""
    if shift is None:
        return t * d
    return (t * d + (1 << (shift - 1))) >> shift


def _combine(
    tab: Any,
    idx: Sequence[IntArray],
    frac: Sequence[Any],
    splits: npt.NDArray[np.uint8] | None,
    shift: int | None,
) -> Any:
    """Interpolate ``tab`` inside the located cells.

    1 and 3 inputs: (multi)linear. 2 inputs: linear on the two triangles of each cell, split
    along the diagonal ``splits`` names (0: (0,0)-(1,1), 1: (1,0)-(0,1)); the generated code
    uses the same formula, term for term. A min-AND rule base
    has creases exactly on such diagonals, where a bilinear patch would only converge like h.
    In Q15 (``shift`` set) every product is rounded on its own, as the C does, and the
    result saturated to int16.
    """
    one: Any = 1.0 if shift is None else (1 << shift)
    d = len(idx)
    if d == 1:
        v0, v1 = tab[idx[0]], tab[idx[0] + 1]
        out = v0 + _lerp_term(frac[0], v1 - v0, shift)
    elif d == 2:
        i, j = idx
        t0, t1 = frac
        v00, v10 = tab[i, j], tab[i + 1, j]
        v01, v11 = tab[i, j + 1], tab[i + 1, j + 1]
        anti = np.zeros(i.shape, dtype=bool) if splits is None else splits[i, j].astype(bool)
        # An anti-diagonal cell is the mirror image (along input 0) of a main-diagonal one, so
        # one formula serves both, without branches in the C: the triangle's middle corner vm,
        # the larger fraction along the edge to it and the smaller along the edge after it.
        s0 = np.where(anti, one - t0, t0)
        w00 = np.where(anti, v10, v00)
        w10 = np.where(anti, v00, v10)
        w01 = np.where(anti, v11, v01)
        w11 = np.where(anti, v01, v11)
        lower = s0 >= t1
        vm = np.where(lower, w10, w01)
        hi = np.where(lower, s0, t1)
        lo = np.where(lower, t1, s0)
        out = w00 + _lerp_term(hi, vm - w00, shift) + _lerp_term(lo, w11 - vm, shift)
    else:
        # Trilinear, reduced axis by axis from the last, as the C does.
        corners: dict[tuple[int, ...], Any] = {}
        for bits in np.ndindex(*(2,) * d):
            corners[bits] = tab[tuple(idx[a] + bits[a] for a in range(d))]
        for axis in reversed(range(d)):
            reduced: dict[tuple[int, ...], Any] = {}
            for bits in np.ndindex(*(2,) * axis):
                a0 = corners[(*bits, 0)]
                a1 = corners[(*bits, 1)]
                reduced[bits] = a0 + _lerp_term(frac[axis], a1 - a0, shift)
            corners = reduced
        out = corners[()]
    if shift is not None:
        out = np.clip(out, -32768, 32767)
    return np.array(out)
