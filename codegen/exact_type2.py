"""Exact interval type-2 inference as constant-time generated code (``--method exact``).

The generated code is the exact IT2 engine's compiled kernel (:mod:`fuzzkit.fuzzy.type2_kernel`)
with every size fixed at generation time, from the same layouts (``FiringLayout``,
``OutputLayout``): fuzzification and firing intervals; each output term's upper and lower
level; in every elementary interval of each set's geometry the interval's ends and the
candidate cut points (an edge meeting a level, or two scaled edges meeting), clamped into the
interval and sorted by a fixed compare-exchange network; the two sets' points merged in a
fixed number of steps; both sets read at every point; prefix sums; the Karnik-Mendel ends by
a binary-search bracket of a fixed number of steps, then on the bracketing piece (where
``g`` is a cubic, whose four coefficients are computed once) a fixed number of bisection
steps, one Horner evaluation each: after ``n`` steps the root is within ``h 2^-(n+1)`` of the
answer (``h`` the piece's width), whatever the input. Every loop's trip
count is a constant; no heap, no recursion.

Covered: one Mamdani output, continuous Karnik-Mendel (or EKM, the same interval),
piecewise-linear terms, conjunctive antecedents. Anything else is refused with the reason
(:func:`unsupported_reason`).
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass

import numpy as np

from fuzzkit.codegen.emit import (
    _comment_safe,
    check_identifier,
    check_module_name,
    check_name,
    render_files,
    source_sha256,
    units_comment,
    units_line,
)
from fuzzkit.codegen.names import names_note, symbol
from fuzzkit.codegen.rounding import EXACT_NUMBER_TYPES, ROUNDING_BOUND
from fuzzkit.codegen.target import load_target
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.type2_kernel import FiringLayout, OutputLayout
from fuzzkit.fuzzy.type2_model import Type2RuleBase

#: Bisection steps on the bracketing piece, per number type. On the piece ``g`` is the cubic
#: ``g(p + t) = g(p) + D(p) t + sign (W(p) t^2 / 2 + W' t^3 / 6)`` (its coefficients are computed
#: once, then each step is one Horner evaluation and a sign test): ``n`` steps leave the
#: midpoint within ``h 2^-(n+1)`` of the root, ``h`` the piece's width, at most twice the full
#: scale ``S``. So the root's error is at most ``S 2^-n``: ``S 2^-50`` in double, ``S 2^-21`` in
#: float, 1/64 of the rounding bound (``ROUNDING_BOUND``: ``S 2^-44``, ``S 2^-15``).
ROOT_STEPS = {"double": 50, "float": 21}


@dataclass(frozen=True)
class Type2Input:
    """One input as the header lists it."""

    index: int
    name: str
    low: str
    high: str


@dataclass(frozen=True)
class Type2Set:
    """One output set's geometry (upper or lower): ``m`` elementary intervals of ``k`` slots,
    ``c`` candidate points per interval."""

    m: int
    k: int
    c: int
    z0: tuple[str, ...]
    z1: tuple[str, ...]
    slot: tuple[str, ...]
    slope: tuple[str, ...]
    icpt: tuple[str, ...]
    root: tuple[str, ...]


@dataclass(frozen=True)
class Type2Spec:
    """Everything the IT2 exact templates use (the header's fields are the type-1 exact
    header's, which the C target reuses)."""

    name: str
    upper: str
    target: str
    number_type: str
    ctype: str
    fsuffix: str
    version: str
    source_file: str
    source_sha256: str
    source_name: str
    names_note: str
    description: tuple[str, ...]
    n_inputs: int
    n_outputs: int
    inputs: tuple[Type2Input, ...]
    outputs: tuple[Type2Input, ...]
    clamp: bool
    extend_limit: str
    libm: tuple[str, ...]
    own_math: tuple[str, ...]
    bound_note: tuple[str, ...]
    has_fpi: bool
    fpi_note: str
    fpi_defaults: dict[str, str] | None
    helpers: tuple[str, ...]
    stack_bytes: int
    units_line: str
    input_units: tuple[str, ...]
    output_units: tuple[str, ...]
    zero: str
    one: str
    half: str
    tiny: str
    # firing
    n_t: int
    n_rules: int
    n_leaves: int
    and_product: bool
    in_low: tuple[str, ...]
    in_high: tuple[str, ...]
    upper_forms: tuple[str, ...]
    lower_forms: tuple[str, ...]
    heights: tuple[str, ...]
    weights: tuple[str, ...]
    leaf_input: tuple[str, ...]
    leaf_term: tuple[str, ...]
    # output
    n_terms: int
    n_inst: int
    inst_rule: tuple[str, ...]
    inst_term: tuple[str, ...]
    product: bool
    sets: tuple[Type2Set, Type2Set]
    n_points: int
    bracket_steps: int
    root_steps: int
    default: str
    #: the generated Python module's inference (the type-1 exact module's own otherwise)
    python_body: str = "exact_type2_body.py.jinja"
    aggregation: str = "max"  # the only one IT2 validation accepts


def _layouts(rb: RuleBase) -> tuple[FiringLayout, OutputLayout] | None:
    """The exact IT2 engine's compiled layouts of ``rb``'s firing and its one continuous
    Mamdani output (what the generated code is made of), or None where it has none."""
    from fuzzkit.fuzzy.type2_inference import _Type2Mamdani

    engine = Engine(rb)._type2
    if engine is None or engine.compiled is None or len(engine.outputs) != 1:
        return None
    out = engine.outputs[0]
    if not isinstance(out, _Type2Mamdani) or not out.continuous:
        return None
    return engine.compiled, out.layout


def unsupported_reason(rb: RuleBase) -> str | None:
    """Why the IT2 exact method cannot emit ``rb`` (None when it can)."""
    if not isinstance(rb, Type2RuleBase):
        return "not an interval type-2 rule base"
    fp = rb.footprint
    if len(rb.outputs) != 1 or rb.outputs[0].is_sugeno:
        return "the exact IT2 emitter takes one Mamdani output"
    if fp.resolution is not None:
        return "resolution: N (discrete type reduction) is generated as a table"
    if fp.type_reduction not in ("karnik-mendel", "ekm"):
        return f"type reduction {fp.type_reduction} is generated as a table"
    if _layouts(rb) is None:
        return (
            "the exact IT2 emitter takes piecewise-linear terms and conjunctive antecedents (no or)"
        )
    return None


def build_type2_spec(rb: RuleBase, target: str, number_type: str = "double") -> Type2Spec:
    """Collect, check and format everything the IT2 exact templates of ``target`` need.

    Raises
    ------
    CodegenError
        Unknown target, Q15, a name that cannot be an identifier, or a rule base the method
        does not cover (:func:`unsupported_reason`).
    """
    from fuzzkit import __version__
    from fuzzkit.fuzzy.type2_kernel import _FIRE_HEADER, _OUT_HEADER

    tg = load_target(target)
    tg.check_number_type(number_type, f"--type {number_type}")
    if number_type not in EXACT_NUMBER_TYPES:
        raise CodegenError(f"rule base {rb.name!r}: --method exact computes in float or double")
    why = unsupported_reason(rb)
    if why is not None:
        raise CodegenError(f"rule base {rb.name!r}: --method exact: {why}")
    name = check_module_name(check_identifier(symbol(rb.name), "rule base name"))
    for var in rb.inputs + rb.outputs:
        check_name(var.name, f"variable name ({rb.name})")
    layouts = _layouts(rb)
    if layouts is None:  # pragma: no cover - unsupported_reason said so above
        raise CodegenError(f"rule base {rb.name!r}: --method exact: no compiled IT2 layout")
    firing, output = layouts
    ff, fi = firing.floats, firing.ints
    lf, li = output.floats, output.ints

    def lit(v: float) -> str:
        return tg.literal(float(v), number_type)

    def lits(a: np.ndarray) -> tuple[str, ...]:
        return tuple(lit(v) for v in np.ravel(a))

    def ints(a: np.ndarray) -> tuple[str, ...]:
        return tuple(str(int(v)) for v in np.ravel(a))

    n_in, n_t, n_rules, n_leaves = (int(v) for v in fi[:4])
    rl = n_rules * n_leaves
    tf = n_in * n_t * 4
    h0 = 2 * n_in + 2 * tf
    limit = membership.EXTEND_LIMIT if number_type == "double" else 1e30
    low = np.maximum(ff[:n_in], -limit)
    high = np.minimum(ff[n_in : 2 * n_in], limit)
    product = bool(li[0])
    n_terms, n_inst = int(li[2]), int(li[3])
    sets = []
    fo, io = 0, _OUT_HEADER + 2 * n_inst
    for side in range(2):
        m, k = int(li[4 + 2 * side]), int(li[5 + 2 * side])
        mk = m * k
        z0, z1 = lf[fo : fo + m], lf[fo + m : fo + 2 * m]
        base = fo + 2 * m
        c = 2 + (k * (k - 1) // 2 if product else k * k)
        sets.append(
            Type2Set(
                m=m,
                k=k,
                c=c,
                z0=lits(z0),
                z1=lits(z1),
                slot=ints(li[io : io + mk]),
                slope=lits(lf[base : base + mk]),
                icpt=lits(lf[base + mk : base + 2 * mk]),
                root=lits(lf[base + 2 * mk : base + 3 * mk]),
            )
        )
        fo += 2 * m + 3 * mk
        io += mk
    n_points = sum(s.m * s.c for s in sets)
    steps = ROOT_STEPS[number_type]
    bracket = math.ceil(math.log2(n_points + 1))
    o = rb.outputs[0]
    file_name, sha = source_sha256(rb)
    real = 8 if number_type == "double" else 4
    bound = ROUNDING_BOUND[number_type]
    note = (
        f"Exact interval type-2 inference (continuous Karnik-Mendel): |generated - exact "
        f"engine| <= {bound:.3g} x the output's full scale (rounding; compile --verify checks 1e5 "
        f"points plus edges). Constant time: {n_points} cut points, a {bracket}"
        f"-step binary-search bracket per end, then {steps} bisection steps on the bracketing "
        f"piece, where g is a cubic in closed form: the root's error is at most the piece's "
        f"width x 2^-{steps + 1}, below the rounding bound."
    )
    fpi = n_in == 2
    return Type2Spec(
        name=name,
        upper=name.upper(),
        target=target,
        number_type=number_type,
        ctype=tg.type_names[number_type],
        fsuffix=tg.math_suffix[number_type],
        version=__version__,
        source_file=_comment_safe(file_name),
        source_sha256=sha,
        source_name=rb.name,
        names_note=names_note(rb.name),
        description=tuple(textwrap.wrap(_comment_safe(" ".join(rb.description.split())), 88)[:8]),
        n_inputs=n_in,
        n_outputs=1,
        inputs=tuple(
            Type2Input(i, v.name, lit(v.low), lit(v.high)) for i, v in enumerate(rb.inputs)
        ),
        outputs=(Type2Input(0, o.name, lit(o.low), lit(o.high)),),
        clamp=rb.out_of_range == "clamp",
        extend_limit=lit(limit),
        libm=(),
        own_math=(),
        bound_note=tuple(textwrap.wrap(note, 88)),
        has_fpi=fpi,
        fpi_note="" if fpi else "No fuzzy-PI step: it needs exactly two inputs",
        fpi_defaults=None,
        helpers=("finite",),
        stack_bytes=real * (4 * n_points + 2 * n_rules + 2 * n_terms + n_in + 16),
        units_line=units_line(rb),
        input_units=tuple(units_comment(v.units) for v in rb.inputs),
        output_units=(units_comment(o.units),),
        zero=lit(0.0),
        one=lit(1.0),
        half=lit(0.5),
        tiny=lit(1e-300) if number_type == "double" else lit(0.0),
        n_t=n_t,
        n_rules=n_rules,
        n_leaves=n_leaves,
        and_product=bool(fi[4]),
        in_low=lits(low),
        in_high=lits(high),
        upper_forms=lits(ff[2 * n_in : 2 * n_in + tf]),
        lower_forms=lits(ff[2 * n_in + tf : 2 * n_in + 2 * tf]),
        heights=lits(ff[h0 : h0 + n_in * n_t]),
        weights=lits(ff[h0 + n_in * n_t : h0 + n_in * n_t + n_rules]),
        leaf_input=ints(fi[_FIRE_HEADER : _FIRE_HEADER + rl]),
        leaf_term=ints(fi[_FIRE_HEADER + rl : _FIRE_HEADER + 2 * rl]),
        n_terms=n_terms,
        n_inst=n_inst,
        inst_rule=ints(li[_OUT_HEADER : _OUT_HEADER + n_inst]),
        inst_term=ints(li[_OUT_HEADER + n_inst : _OUT_HEADER + 2 * n_inst]),
        product=product,
        sets=(sets[0], sets[1]),
        n_points=n_points,
        bracket_steps=bracket,
        root_steps=steps,
        default=tg.nan if o.default is None else lit(float(o.default)),
    )


def emit_exact_type2(rb: RuleBase, target: str, number_type: str = "double") -> dict[str, str]:
    """The IT2 exact-method ``target`` sources for ``rb``: ``{relative path: text}``."""
    spec = build_type2_spec(rb, target, number_type)
    return render_files(target, spec.name, spec, "exact_type2")


__all__ = [
    "ROOT_STEPS",
    "Type2Spec",
    "build_type2_spec",
    "emit_exact_type2",
    "unsupported_reason",
]
