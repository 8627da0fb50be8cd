"""Choosing how a rule base is compiled: a lookup table, the exact inference, or ``auto``.

``auto`` (the default of ``fuzzkit compile``) takes the table when one meets the tolerance
within the size budget (``max_bytes``) and the exact method otherwise, and says why. Mean,
smallest and largest of maximum are discontinuous (the result jumps where two maxima swap), so
a piecewise-linear table's honest bound there is a large share of the range: ``auto`` takes the
exact method for them and ``table`` refuses them unless a resolution is given, in which case it
warns with the measured bound.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from fuzzkit.codegen.emit import FpiDefaults, emit
from fuzzkit.codegen.exact import DISCONTINUOUS, emit_exact, unsupported_reason
from fuzzkit.codegen.lookup_table import (
    DEFAULT_MAX_POINTS,
    DEFAULT_TOLERANCE,
    Evaluator,
    LookupTable,
    NumberType,
    percent,
)
from fuzzkit.codegen.progress import ProgressFn
from fuzzkit.codegen.table_search import ReferenceEvaluator, make_table, table_problem
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.type2_model import Type2RuleBase

METHODS = ("auto", "table", "exact")
#: Size budget of ``auto`` for a table's constant data (a small microcontroller's share).
DEFAULT_MAX_BYTES = 8192
#: Defuzzifiers whose surface jumps (``exact.DISCONTINUOUS``): no table is made for them silently.
_VALUE_BYTES = {"float": 4, "double": 8, "q15": 2}


@dataclass(frozen=True)
class Compiled:
    """What ``compile_rulebase`` made: the method used, the files, the table if any, and notes."""

    method: str
    files: dict[str, str]
    table: LookupTable | None
    #: why this method, as a clause that follows "because"
    reason: str
    warnings: tuple[str, ...] = ()


def compile_rulebase(
    rb: RuleBase,
    target: str,
    number_type: NumberType,
    *,
    method: str = "auto",
    tolerance: float | None = None,
    resolution: int | Sequence[int] | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
    fpi_defaults: FpiDefaults | None = None,
    progress: ProgressFn | None = None,
) -> Compiled:
    """Generate ``target`` sources for ``rb`` by ``method`` (see the module docstring).

    ``progress`` is told how the table search goes (see ``table_search.ProgressFn``).

    Raises
    ------
    CodegenError
        Unknown method, a method that cannot compile this rule base (with the reason), or a
        table that cannot meet the tolerance.
    """
    if method not in METHODS:
        raise CodegenError(f"unknown --method {method!r} (expected one of {', '.join(METHODS)})")
    if max_bytes <= 0:
        raise CodegenError(f"--max-bytes must be a positive number of bytes, got {max_bytes}")
    exact_why = unsupported_reason(rb, number_type)
    if method == "exact":
        return _exact(rb, target, number_type, fpi_defaults, "you asked for it (--method exact)")
    table_why = table_problem(rb, number_type)
    discontinuous = rb.defuzzifier in DISCONTINUOUS
    if method == "table":
        if table_why is not None:
            raise CodegenError(f"rule base {rb.name!r}: --method table: {table_why}")
        if discontinuous and resolution is None:
            raise CodegenError(
                f"rule base {rb.name!r}: {rb.defuzzifier} is discontinuous (the result jumps "
                "where two maxima swap), so no table meets a useful tolerance: use --method "
                "exact (or give --resolution to get a table with its measured bound)"
            )
        table = make_table(
            rb,
            number_type=number_type,
            tolerance=tolerance,
            resolution=resolution,
            max_points=IT2_SEARCH_POINTS if isinstance(rb, Type2RuleBase) else DEFAULT_MAX_POINTS,
            progress=progress,
        )
        warnings: tuple[str, ...] = ()
        if discontinuous:
            worst = max(
                b / (hi - lo) for b, (lo, hi) in zip(table.bound, table.output_ranges, strict=True)
            )
            warnings = (
                f"warning: {rb.defuzzifier} is discontinuous; this table's verified bound is "
                f"{100 * worst:.3g} % of the output range (--method exact has rounding error only)",
            )
        files = emit(rb, table, target, fpi_defaults=fpi_defaults)
        return Compiled("table", files, table, "you asked for one (--method table)", warnings)
    # auto
    if exact_why is None:
        if isinstance(rb, Type2RuleBase) and resolution is None:
            return _exact(
                rb, target, number_type, fpi_defaults,
                "an interval type-2 surface is steep and kinked (a 65 x 65 table certifies "
                "0.7 % of the range): exact IT2 inference has rounding error only",
            )  # fmt: skip
        if discontinuous:
            return _exact(
                rb, target, number_type, fpi_defaults,
                f"{rb.defuzzifier} is discontinuous and a table cannot follow its jumps",
            )  # fmt: skip
        if table_why is not None:
            return _exact(
                rb, target, number_type, fpi_defaults, f"no table can be made: {table_why}"
            )
    elif table_why is not None:
        raise CodegenError(
            f"rule base {rb.name!r} cannot be compiled: the exact method: {exact_why}; "
            f"a table: {table_why}"
        )
    elif discontinuous and resolution is None:
        # no table follows the jumps, so a search for one would spend its whole budget
        raise CodegenError(
            f"rule base {rb.name!r} cannot be compiled: the exact method: {exact_why}; a "
            f"table: {rb.defuzzifier} is discontinuous (the result jumps where two maxima "
            "swap), so no table meets a useful tolerance (give --resolution to get one with "
            "its measured bound)"
        )
    tol = DEFAULT_TOLERANCE if tolerance is None else tolerance
    per_point = _VALUE_BYTES[number_type] * len(rb.outputs)
    # one evaluator for every search of this compile: one engine, and one engine budget
    # (codegen.budget) however many searches the method tries
    reference = ReferenceEvaluator(rb)
    if resolution is not None:  # the user chose the table's size: its errors are theirs to see
        table = make_table(
            rb,
            number_type=number_type,
            tolerance=tolerance,
            resolution=resolution,
            evaluate=reference,
            progress=progress,
        )
    else:
        try:
            table = make_table(
                rb,
                number_type=number_type,
                tolerance=tol,
                max_points=max(8, max_bytes // per_point),
                evaluate=reference,
                progress=progress,
            )
        except CodegenError:
            if exact_why is not None:
                # No exact alternative (Q15, say): a table over the budget beats no code; the
                # reason printed says it is over --max-bytes.
                table = _over_budget_table(rb, number_type, tol, exact_why, reference, progress)
                files = emit(rb, table, target, fpi_defaults=fpi_defaults)
                return Compiled(
                    "table",
                    files,
                    table,
                    f"the exact method cannot be used ({exact_why}), so it takes the "
                    f"{table.memory_bytes}-byte table that meets the tolerance of "
                    f"{percent(tol)} of the output range, over --max-bytes {max_bytes}",
                )
            return _exact(
                rb, target, number_type, fpi_defaults,
                f"no table within --max-bytes {max_bytes} meets the tolerance of "
                f"{percent(tol)} of the output range",
            )  # fmt: skip
    if table.memory_bytes > max_bytes and exact_why is None and resolution is None:
        return _exact(
            rb, target, number_type, fpi_defaults,
            f"the table that meets the tolerance of {percent(tol)} of the output range needs "
            f"{table.memory_bytes} bytes, more than --max-bytes {max_bytes}",
        )  # fmt: skip
    files = emit(rb, table, target, fpi_defaults=fpi_defaults)
    why = (
        f"a {table.memory_bytes}-byte table meets the tolerance of {percent(tol)} of the "
        f"output range within --max-bytes {max_bytes}"
        if resolution is None
        else "you chose its size (--resolution)"
    )
    if exact_why is not None:
        why += f", and the exact method cannot be used ({exact_why})"
    return Compiled("table", files, table, why)


#: The largest table searched for an interval type-2 rule base (by --method table, and by
#: the auto method over --max-bytes where the exact method cannot compile one): the IT2
#: surface is steep and kinked, and the full search (65536 points) certified 18 million
#: engine points, minutes of CPU, before refusing ``macvicar_whelan_it2``; 8192 points
#: certify 0.8 million (seconds).
IT2_SEARCH_POINTS = 8192


def _over_budget_table(
    rb: RuleBase,
    number_type: NumberType,
    tol: float,
    exact_why: str,
    reference: Evaluator,
    progress: ProgressFn | None,
) -> LookupTable:
    """The table that meets ``tol`` whatever its size (an IT2 rule base: up to
    :data:`IT2_SEARCH_POINTS`), when no table within --max-bytes does and the exact method
    cannot be used; ``reference`` is the compile's evaluator, whose budget the first search
    has already been charged to."""
    if not isinstance(rb, Type2RuleBase):
        return make_table(
            rb, number_type=number_type, tolerance=tol, evaluate=reference, progress=progress
        )
    try:
        return make_table(
            rb,
            number_type=number_type,
            tolerance=tol,
            max_points=IT2_SEARCH_POINTS,
            evaluate=reference,
            progress=progress,
        )
    except CodegenError as exc:
        raise CodegenError(
            f"rule base {rb.name!r} cannot be compiled by --method auto: the exact method: "
            f"{exact_why}; a table: {exc} (the search for an interval type-2 table stops at "
            f"{IT2_SEARCH_POINTS} points: give --resolution N for a table of N breakpoints per "
            "input with its certified bound, or a larger --tolerance)"
        ) from None


def _exact(
    rb: RuleBase,
    target: str,
    number_type: str,
    fpi_defaults: FpiDefaults | None,
    reason: str,
) -> Compiled:
    files = emit_exact(rb, target, number_type, fpi_defaults=fpi_defaults)
    return Compiled("exact", files, None, reason)
