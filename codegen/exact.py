"""The exact method: the inference itself as C or Python, no table (``--method exact``).

:func:`build_exact_spec` precomputes in Python everything the generated code can take as data:
the fuzzification constants of every input term, each rule's antecedent as an expression over
the memberships, which rules feed which output piece, and for piecewise-linear outputs the
engine's own elementary intervals with the line (slope, root) of every piece in them
(``fuzzkit.fuzzy.inference.PiecewiseLinearGeometry``, the same breakpoint sweep). The templates
(``backends/<target>/exact.*.jinja``) only lay that out; at run time the code intersects the
firing levels with those lines, sorts the few points of each interval, and integrates the
aggregated set exactly between them (trapezoid and moment formulas, Gauss-Legendre for the
probabilistic sum), as the engine does. Everything is bounded at generation time: array sizes,
loop counts (insertion sort of at most ``points_per_interval`` values, 60 bisection steps for a
probabilistic-sum bisector), so the worst-case time is constant; nothing is allocated.

The error against the exact engine is rounding only; :data:`ROUNDING_BOUND` states it. Gaussian
outputs under a probabilistic sum (product implication, centroid) are integrated by the fixed
Gauss-Legendre rule of ``fuzzkit.fuzzy.smooth_quadrature``, which the engine uses too; its proven
error against the true centroid is printed in the header.

Size: just over 800 lines, all for one idea: the engine's output-stage breakpoint sweep emitted
as generated-code data, with its rounding bound.
"""

from __future__ import annotations

import itertools
import math
import textwrap
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fuzzkit.codegen.emit import (
    FPI_GAIN_KEYS,
    FpiDefaults,
    _check_float32_gains,
    _comment_safe,
    _wrap,
    check_identifier,
    check_module_name,
    check_name,
    render_files,
    source_sha256,
    units_comment,
    units_line,
)
from fuzzkit.codegen.names import names_note, symbol

# the number types and the rounding bound every exact unit (type-1, IT2) states, defined once
from fuzzkit.codegen.rounding import EXACT_NUMBER_TYPES, ROUNDING_BOUND, ROUNDING_ULPS
from fuzzkit.codegen.target import Target, load_target
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy import membership, shapes
from fuzzkit.fuzzy.gaussian_geometry import GaussianGeometry, quadratic
from fuzzkit.fuzzy.gaussian_geometry import applies as gaussian_applies
from fuzzkit.fuzzy.inference import OutputPieces, PiecewiseLinearGeometry, partition_centroid
from fuzzkit.fuzzy.model import (
    Compound,
    Expression,
    Proposition,
    Rule,
    RuleBase,
    Term,
    Variable,
)
from fuzzkit.fuzzy.output_geometry import LINEAR_NODES, TIE
from fuzzkit.fuzzy.smooth_quadrature import Quadrature, terms_at_nodes
from fuzzkit.fuzzy.smooth_quadrature import applies as quadrature_applies
from fuzzkit.fuzzy.type2_model import Type2RuleBase

#: Defuzzifiers the exact method emits (``weighted_sum`` and ``weighted_average`` of Sugeno
#: outputs: every consequent's value, a constant or ``c . x + c0``, weighted by its rule's
#: firing strength, as ``fuzzkit.fuzzy.sugeno``).
EXACT_DEFUZZIFIERS = (
    "centroid",
    "bisector",
    "mean_of_maximum",
    "smallest_of_maximum",
    "largest_of_maximum",
    "weighted_average",
    "weighted_sum",
)
#: Fuzzification kinds the exact templates implement (a shape's registry record says which
#: one it uses, ``fuzzkit.fuzzy.shapes.ExactForm``; a shape without one is refused).
TEMPLATE_KINDS = (
    "linear",
    "singleton",
    "gaussian",
    "gaussian_product",
    "bell",
    "sigmoid",
    "sigmoid_difference",
    "sigmoid_product",
    "s_shape",
    "z_shape",
    "pi_shape",
)
#: Input kinds that call a helper of the generated code: the S spline (``smf``), the sigmoid.
KIND_HELPERS = {
    "s_shape": "smf",
    "z_shape": "smf",
    "pi_shape": "smf",
    "sigmoid_difference": "sigmf",
    "sigmoid_product": "sigmf",
}


@dataclass(frozen=True)
class ExactTerm:
    """One input term as the templates need it: its kind and its constants as literals."""

    index: int  # position in the flat membership array
    name: str
    kind: str  # one of TEMPLATE_KINDS
    params: tuple[str, ...]


@dataclass(frozen=True)
class ExactInput:
    """One input: its clamp (or extend) limits and its terms."""

    index: int
    name: str
    low: str
    high: str
    terms: tuple[ExactTerm, ...]


@dataclass(frozen=True)
class ExactRule:
    """One rule: its firing strength as an expression over ``mu[...]`` (weight applied)."""

    index: int
    text: str
    expr: str


@dataclass(frozen=True)
class ExactOutput:
    """One output: how its piece levels come from the rules and how it is defuzzified."""

    index: int
    name: str
    low: str
    high: str
    default: str
    defuzzifier: str
    n_pieces: int
    level_exprs: tuple[str, ...]  # weighted average: term activations; else piece levels
    centres: tuple[str, ...]  # weighted average only
    # Piecewise-linear geometry (empty for weighted average and for outputs no rule feeds)
    n_intervals: int
    slots: int
    z: tuple[str, ...]
    slot_piece: tuple[str, ...]
    slope: tuple[str, ...]
    anchor: tuple[str, ...]  # per slot: its line's root (slope 0: its value)
    candidates: int
    points: int  # points per interval after the crossings (bounded sum)
    gl_nodes: tuple[str, ...]
    gl_weights: tuple[str, ...]
    empty: bool
    # Grid rules: the consequent term of each (row, column) cell (n_terms = none)
    grid_cons: tuple[str, ...] = ()
    # Polynomial centroid (partition-style min/max outputs): the engine's own fast centroid
    poly: PolySpec | None = None
    # Sugeno: per consequent (rule index, input coefficients, constant), in the engine's order
    sugeno: tuple[SugenoTerm, ...] = ()
    # Gaussian terms, max aggregation, centroid: closed form (erfc)
    gauss: GaussSpec | None = None
    # Gaussian terms, product implication, probabilistic sum, centroid: a fixed quadrature
    quad: QuadSpec | None = None


@dataclass(frozen=True)
class QuadSpec:
    """The composite Gauss-Legendre rule of ``codegen.smooth_quadrature``: its nodes and
    weights, and per piece its Gaussian at every node (piece-major), with the proven bound."""

    n_nodes: int
    nodes: tuple[str, ...]
    weights: tuple[str, ...]
    table: tuple[str, ...]
    cells: int
    per_cell: int
    bound: float  # |centroid error| in output units, before rounding


@dataclass(frozen=True)
class GaussSpec:
    """Gaussian output terms under max aggregation, for the centroid in closed form (as
    ``fuzzkit.fuzzy.gaussian_geometry``): per piece its term's mean and sigma, the points
    where two unscaled terms cross, and how many points a call sorts."""

    means: tuple[str, ...]
    sigmas: tuple[str, ...]
    fixed: tuple[str, ...]
    n_points: int
    product: bool
    #: product implication: per pair of pieces (i, j) where L_i g_i = L_j g_j, the quadratic
    #: a y^2 + b y + c0 + ln(L_i / L_j) = 0 (``gaussian_geometry._crossings_batch``)
    pairs: tuple[tuple[int, int, str, str, str], ...]
    linear: tuple[bool, ...]  # per pair: a == 0
    sqrt2: str
    sqrt_half_pi: str
    peaks: tuple[str, ...]  # per piece: where its term is largest in the range
    gpeaks: tuple[str, ...]  # and its value there
    keep: str  # 1 - TIE: values at least this share of the height are maximal


@dataclass(frozen=True)
class SugenoTerm:
    """One consequent of a Sugeno output: ``w[rule] * (coefficients . x + constant)``."""

    rule: int
    coefficients: tuple[tuple[int, str], ...]  # (input index, literal) of each non-zero one
    constant: str


@dataclass(frozen=True)
class PolySpec:
    """Area and moment of each clipped function as piecewise cubics in its level.

    Functions are the output terms, then the overlaps of term pairs (level = the smaller of
    the two, sign -1): max(g_i) = sum g_i - sum min(g_i, g_j) when at most two terms overlap.
    """

    n_funcs: int
    pieces: int
    level_a: tuple[str, ...]  # index of the level (term), per function
    level_b: tuple[str, ...]  # the pair's other term (same as level_a for a term)
    sign: tuple[str, ...]
    starts: tuple[str, ...]
    inv_width: tuple[str, ...]
    area: tuple[str, ...]  # 4 coefficients per piece, constant first
    moment: tuple[str, ...]
    low: str
    width: str
    #: With window inputs (2 x 2 cells fire): the functions that can be non-zero for each
    #: block of cells, as a set number per block (indexed like the cells by its first cell)
    #: and per set its function count and up to ``set_width`` function numbers (ascending).
    block_set: tuple[str, ...] = ()
    set_count: tuple[str, ...] = ()
    set_funcs: tuple[str, ...] = ()
    set_width: int = 0
    index_type: str = "unsigned char"


@dataclass(frozen=True)
class ExactSpec:
    """Everything an exact-method template may use; nothing else reaches the generated text."""

    name: str
    upper: str
    target: str
    number_type: str
    ctype: str
    fsuffix: str  # libm suffix: "f" for float, "" for double
    version: str
    source_file: str
    source_sha256: str
    #: the rule base's own name, which each file's first line quotes (codegen.provenance)
    source_name: str
    #: the header's sentence on a mangled rule-base name (codegen.names), or ""
    names_note: str
    description: tuple[str, ...]
    n_inputs: int
    n_outputs: int
    n_mu: int
    n_rules: int
    inputs: tuple[ExactInput, ...]
    rules: tuple[ExactRule, ...]
    outputs: tuple[ExactOutput, ...]
    implication: str
    aggregation: str
    clamp: bool
    libm: tuple[str, ...]
    #: math functions the code computes itself (``Target.portable_math``), not taken from libm
    own_math: tuple[str, ...]
    bound_note: tuple[str, ...]
    has_fpi: bool
    fpi_note: str
    fpi_defaults: dict[str, str] | None
    zero: str
    one: str
    half: str
    tie: str
    tiny: str
    bisect_margin: str
    extend_limit: str
    vertical: str
    stack_bytes: int
    helpers: tuple[str, ...]  # helper functions the code calls (min, max, psum, finite, smf, sigmf)
    has_geometry: bool
    max_base: int  # largest count of interval points before the bounded-sum crossings
    piece_type: str
    two: str
    #: the engine's two Gauss-Legendre nodes and weights of a linear segment (on [-1, 1])
    line_nodes: tuple[str, str]
    line_weights: tuple[str, str]
    and_: str
    or_: str
    weighted: bool
    grid: bool  # rules form a 2-input table: loop over the non-zero memberships only
    grid_weights: tuple[str, ...]
    n_terms0: int
    n_terms1: int
    windows: tuple[WindowSpec, ...]  # grid rules on two window inputs: visit 2 x 2 cells
    #: a Sugeno output has a linear term: the code keeps the input values the terms see
    keeps_inputs: bool = False
    #: the Sugeno stage's type: double in float code under ``extend`` (:func:`wide_sugeno`)
    sugeno_type: str = "double"
    sugeno_wide: bool = False
    sugeno_extend_limit: str = ""
    #: "e [N], de [N], du [mm]" when any variable has units, else "" (as the table's header)
    units_line: str = ""
    input_units: tuple[str, ...] = ()  # " [N]" or "" per input
    output_units: tuple[str, ...] = ()


#: What the exact method does not emit yet, one entry per class of type-1 rule base it refuses
#: (:func:`not_yet` says which; :func:`unsupported_reason` words it). Everything else the
#: engine evaluates, the method emits. tests/test_exact_product.py meets exactly these over
#: the product of AND/OR operators x implication x aggregation x defuzzifier x output kind;
#: as each is built its entry goes, until the list is empty.
NOT_YET = {
    "smooth_output": (
        "the exact method integrates piecewise-linear and Gaussian output terms; other smooth "
        "ones (bell, sigmoid, MATLAB's smooth shapes) need a quadrature with a proven error "
        "bound, which is not built yet; use the weighted_average defuzzifier, or --method table"
    ),
    "gaussian_sum": (
        "the exact method integrates Gaussian output terms in closed form under max "
        "aggregation, and by a proven quadrature under a probabilistic sum with product "
        "implication and the centroid; other bounded or probabilistic sums are not built "
        "yet; use max aggregation, the weighted_average defuzzifier, or --method table"
    ),
    "mixed_output": (
        "the exact method integrates an output whose terms are all piecewise linear or all "
        "Gaussian; Gaussian and piecewise-linear terms in one output are not built yet; "
        "use the weighted_average defuzzifier, or --method table"
    ),
    # float only: a + b (1 - a) rounds to a when b is below half an ulp of it, so where the
    # engine's double sees one strict maximum float sees a tie and takes the other end (1-2 %
    # of random points in tests/test_exact_product.py, against the 1 % --verify allows)
    "float_psum_maxima": (
        "in float, a probabilistic sum drops a contribution below half an ulp, so mean, "
        "smallest and largest of maximum can pick another maximum than the engine's double; "
        "maxima of a probabilistic sum in float are not built yet (use --type double)"
    ),
}
#: The defuzzifiers that jump where two maxima tie (mean, smallest and largest of maximum).
DISCONTINUOUS = frozenset({"mean_of_maximum", "smallest_of_maximum", "largest_of_maximum"})


def not_yet(rb: RuleBase, out: Variable, number_type: str = "double") -> tuple[str, Term] | None:
    """Which :data:`NOT_YET` class refuses output ``out`` of ``rb`` in ``number_type``, with the
    term that makes it so (None: the method emits it). An unregistered shape raises."""
    for t in out.terms:
        shapes.shape(t.shape)  # unregistered: raise, whichever path reads the term
    if out.is_sugeno or rb.defuzzifier == "weighted_average":
        return None  # the weighted average needs only the term centres
    if (
        number_type == "float"
        and rb.defuzzifier in DISCONTINUOUS
        and rb.operators.aggregation == "probabilistic_sum"
        and out.terms
    ):
        return "float_psum_maxima", out.terms[0]
    if _gaussian_closed_form(rb, out) or _quadrature_rule(rb, out) is not None:
        return None
    pwl = [t for t in out.terms if shapes.shape(t.shape).piecewise_linear]
    curved = [t for t in out.terms if not shapes.shape(t.shape).piecewise_linear]
    if not curved:
        return None
    other = [t for t in curved if t.shape != "gaussian"]
    if other:
        return "smooth_output", other[0]
    if pwl:
        return "mixed_output", curved[0]
    return "gaussian_sum", curved[0]


def unsupported_reason(rb: RuleBase, number_type: str = "double") -> str | None:
    """Why the exact method cannot compile ``rb`` (None when it can).

    It needs a floating-point number type, a type-1 rule base, and outputs outside the
    :data:`NOT_YET` classes (the weighted average, which only uses the term centres, takes any
    output terms).
    """
    if number_type not in EXACT_NUMBER_TYPES:
        return (
            f"the exact method computes in floating point; --type {number_type} is only "
            "available as a lookup table (use --method table)"
        )
    if isinstance(rb, Type2RuleBase):
        from fuzzkit.codegen.exact_type2 import unsupported_reason as type2_reason

        why = type2_reason(rb)
        return None if why is None else f"{why} (or use --method table)"
    if rb.defuzzifier not in EXACT_DEFUZZIFIERS:
        return f"the exact method has no {rb.defuzzifier} defuzzifier: compile with --method table"
    for out in rb.outputs:
        found = not_yet(rb, out, number_type)
        if found is not None:
            key, term = found
            if key == "float_psum_maxima":  # the operators refuse it, not a term
                return f"output {out.name!r} ({rb.defuzzifier}): {NOT_YET[key]}"
            return (
                f"output {out.name!r} term {term.name!r} is a {term.shape} "
                f"({rb.operators.aggregation} aggregation): {NOT_YET[key]}"
            )
    for var in rb.inputs:
        for term in var.terms:
            if _exact_form(term) is None:
                return _no_exact_form(var, term)
    return None


def _gaussian_closed_form(rb: RuleBase, out: Variable) -> bool:
    """Gaussian terms, max aggregation (any defuzzifier but the weighted average, which only
    needs the centres): the closed form the templates emit."""
    return rb.defuzzifier != "weighted_average" and gaussian_applies(rb, out, OutputPieces(rb, out))


def _quadrature_rule(rb: RuleBase, out: Variable) -> Quadrature | None:
    """The proven quadrature of an output (``fuzzkit.fuzzy.smooth_quadrature``), else None."""
    return quadrature_applies(rb, out, OutputPieces(rb, out))


def _linear(out: Variable) -> bool:
    return any(t.shape == "linear" and any(t.params[:-1]) for t in out.terms)


def wide_sugeno(rb: RuleBase, number_type: str) -> bool:
    """Whether float code computes the Sugeno stage in double: linear terms over inputs that
    are not clamped (``out_of_range: extend``) see every input up to the engine's bound of
    1e100, and their values (and ``c . x`` near FLT_MAX) do not fit a float; the sum is taken
    in double and rounded once to float, so a value beyond float's range comes out as +-inf,
    the float nearest to it."""
    return (
        number_type == "float"
        and rb.out_of_range == "extend"
        and any(o.is_sugeno and _linear(o) for o in rb.outputs)
    )


def _no_exact_form(var: Variable, term: Term) -> str:
    return (
        f"input {var.name!r} term {term.name!r}: the exact method has no generated "
        f"fuzzification for shape {term.shape!r} yet; compile with --method table"
    )


def _exact_form(term: Term) -> shapes.ExactForm | None:
    """How generated code fuzzifies ``term`` (None: it cannot); an unregistered shape raises."""
    form = shapes.shape(term.shape).exact
    if form is not None and form.kind not in TEMPLATE_KINDS:
        raise CodegenError(f"shape {term.shape!r}: no exact template for kind {form.kind!r}")
    return form


class _Lit:
    """Literals of one target and number type (the target's ``literal`` and ``nan``)."""

    def __init__(self, target: Target, number_type: str) -> None:
        self.target = target
        self.number_type = number_type

    def __call__(self, value: float) -> str:
        return self.target.literal(value, self.number_type)

    def maybe_nan(self, value: float | None) -> str:
        if value is None or math.isnan(value):
            return self.target.nan
        return self(float(value))


def _input_terms(var: Variable, offset: int, lit: _Lit, vertical: float) -> tuple[ExactTerm, ...]:
    terms = []
    for j, term in enumerate(var.terms):
        form = _exact_form(term)
        if form is None:
            raise CodegenError(_no_exact_form(var, term))
        values = form.constants(term.params)
        if form.kind == "linear":
            # the engine's 1e200 vertical slope overflows a float: any slope large enough to
            # turn every representable non-zero distance into a step does the same
            b, c, rise, fall = values
            values = (b, c, min(rise, vertical), min(fall, vertical))
        terms.append(ExactTerm(offset + j, term.name, form.kind, tuple(lit(v) for v in values)))
    return tuple(terms)


def _expression(
    expr: Expression, rb: RuleBase, mu_index: dict[tuple[str, str], int], ops: dict[str, str]
) -> str:
    """The antecedent as source text over ``mu[k]`` (AND/OR folded left, as the engine)."""
    if isinstance(expr, Proposition):
        k = mu_index[(expr.variable, expr.term)]
        return f"({ops['one']} - mu[{k}])" if expr.negated else f"mu[{k}]"
    parts = [_expression(e, rb, mu_index, ops) for e in expr.operands]
    acc = parts[0]
    for p in parts[1:]:
        acc = ops[expr.op].format(a=acc, b=p)
    return acc


def _rule_text(expr: Expression) -> str:
    if isinstance(expr, Proposition):
        return f"{expr.variable} is {'not ' if expr.negated else ''}{expr.term}"
    return f" {expr.op} ".join(
        _rule_text(e) if isinstance(e, Proposition) else f"({_rule_text(e)})" for e in expr.operands
    )


def _fold(items: list[str], fmt: str, empty: str) -> str:
    if not items:
        return empty
    acc = items[0]
    for item in items[1:]:
        acc = fmt.format(a=acc, b=item)
    return acc


def grid_rules(rb: RuleBase) -> dict[tuple[int, int], Rule] | None:
    """The rules as a 2-input table ``{(row term, column term): rule}``, or None.

    A table is what lets the generated code visit only the cells whose memberships are both
    non-zero (4 of 49 for a partition): every rule is ``x0 is A and x1 is B`` (no NOT, each cell
    once), and every output's levels are per-term aggregates (max, or bounded sum with product
    implication, or any aggregation for the weighted average).
    """
    ops = rb.operators
    per_term = ops.aggregation == "max" or (
        ops.aggregation == "bounded_sum" and ops.implication == "product"
    )
    if len(rb.inputs) != 2 or not (per_term or rb.defuzzifier == "weighted_average"):
        return None
    if any(o.is_sugeno for o in rb.outputs):  # each consequent counts: no per-term levels
        return None
    names = (rb.inputs[0].name, rb.inputs[1].name)
    cells: dict[tuple[int, int], Rule] = {}
    for rule in rb.rules:
        ante = rule.antecedent
        if not isinstance(ante, Compound) or ante.op != "and" or len(ante.operands) != 2:
            return None
        props = [p for p in ante.operands if isinstance(p, Proposition) and not p.negated]
        by_var = {p.variable: p.term for p in props}
        if len(props) != 2 or set(by_var) != set(names):
            return None
        key = (rb.inputs[0].term_index(by_var[names[0]]), rb.inputs[1].term_index(by_var[names[1]]))
        targets = [c.variable for c in rule.consequents]
        if key in cells or len(set(targets)) != len(targets):
            return None
        cells[key] = rule
    return cells


@dataclass(frozen=True)
class WindowSpec:
    """An input whose non-zero terms are always two neighbours (i, i + 1): where to look.

    ``cuts`` are the term vertices inside the range; ``first[k]`` is the first of the two
    terms for an input with k cuts at or below it; ``terms`` holds (b, c, rise, fall) per term
    (trapezoid form), then a padding term that is 0 everywhere.
    """

    index: int
    name: str
    low: str
    high: str
    n_terms: int
    cuts: tuple[str, ...]
    first: tuple[str, ...]
    terms: tuple[str, ...]


def _window(var: Variable, index: int, lit: _Lit, vertical: float) -> WindowSpec | None:
    if not all(t.is_piecewise_linear for t in var.terms):
        return None
    cuts = sorted(
        {float(p) for t in var.terms for p in membership.breakpoints(t) if var.low < p < var.high}
    )
    edges = [var.low, *cuts, var.high]
    n = len(var.terms)
    first = []
    for k in range(len(edges) - 1):
        probe = [edges[k], 0.5 * (edges[k] + edges[k + 1])]
        if k == len(edges) - 2:
            probe.append(edges[k + 1])
        active = {
            j
            for j, term in enumerate(var.terms)
            for x in probe
            if float(membership.evaluate_term(term, x)) > 0.0
        }
        if not active:
            first.append(n - 1)
        elif max(active) - min(active) > 1:
            return None
        else:
            first.append(min(min(active), n - 1))
    forms = []
    for term in var.terms:
        b, c, rise, fall = membership.trapezoid_form(term)
        forms += [b, c, min(rise, vertical), min(fall, vertical)]
    forms += [vertical, 0.0, 1.0, 0.0]  # 1 + (x - 1e30) * 1 < 0 for every x in range: 0
    return WindowSpec(
        index=index,
        name=var.name,
        low=lit(var.low),
        high=lit(var.high),
        n_terms=n,
        cuts=tuple(lit(c) for c in cuts),
        first=tuple(str(f) for f in first),
        terms=_wrap([lit(v) for v in forms], 4),
    )


def _windows(rb: RuleBase, lit: _Lit) -> tuple[WindowSpec, ...] | None:
    """Both inputs as windows (clamped, piecewise linear, two neighbours), or None."""
    if rb.out_of_range != "clamp":
        return None
    vertical = 1e200 if lit.number_type == "double" else 1e30
    found = [_window(v, i, lit, vertical) for i, v in enumerate(rb.inputs)]
    if any(w is None for w in found):
        return None
    return tuple(w for w in found if w is not None)


def _firing_sets(
    levels: list[tuple[int, int]], cons: list[int], rows: int, columns: int
) -> tuple[list[int], list[list[int]]]:
    """Per block of 2 x 2 cells (first cell (i, j), numbered i * columns + j), the functions
    whose level can be non-zero there: both of its terms are the consequent of a cell of the
    block. Every other function has level 0 and adds exactly 0 (its first piece starts at 0
    with constant coefficient 0). Returns the set number of each block and the distinct sets.
    """
    sets: list[list[int]] = []
    block_set: list[int] = []
    for i in range(rows):
        for j in range(columns):
            cells = [(i + a) * columns + j + b for a in (0, 1) for b in (0, 1)]
            fired = {cons[c] for c in cells if i + 1 < rows and j + 1 < columns}
            funcs = [f for f, (a, b) in enumerate(levels) if a in fired and b in fired]
            if funcs not in sets:
                sets.append(funcs)
            block_set.append(sets.index(funcs))
    return block_set, sets


def _poly(
    rb: RuleBase,
    out: Variable,
    pieces: OutputPieces,
    geo: PiecewiseLinearGeometry,
    lit: _Lit,
    wrap: Callable[[list[str]], tuple[str, ...]],
    cons: list[int] | None,
) -> PolySpec | None:
    if rb.defuzzifier != "centroid":
        return None
    pc = partition_centroid(geo, rb, len(out.terms))
    if pc is None:
        return None
    n_terms = len(out.terms)
    p_max = pc.p_max
    level_a: list[str] = []
    level_b: list[str] = []
    sign: list[str] = []
    starts: list[str] = []
    inv_w: list[str] = []
    area: list[str] = []
    moment: list[str] = []
    for f, sgn, piece in pc.functions:
        a, b = (f, f) if f < n_terms else pc.pairs[f - n_terms]
        level_a.append(str(a))
        level_b.append(str(b))
        sign.append(lit(float(sgn)))
        n = len(piece.starts)
        starts += [lit(v) for v in piece.starts] + [lit(1e30)] * (p_max - n)
        inv_w += [lit(v) for v in piece.inv_width] + [lit(1.0)] * (p_max - n)
        for coefs, dest in ((piece.area, area), (piece.moment, moment)):
            for c in coefs:
                dest += [lit(v) for v in c]
            dest += [lit(0.0)] * (4 * (p_max - n))
    firing: dict[str, object] = {}
    if cons is not None:
        rows, columns = len(rb.inputs[0].terms) + 1, len(rb.inputs[1].terms) + 1
        pairs = [(int(a), int(b)) for a, b in zip(level_a, level_b, strict=True)]
        block_set, sets = _firing_sets(pairs, cons, rows, columns)
        width = max(1, max(len(f) for f in sets))
        firing = dict(
            block_set=_wrap([str(k) for k in block_set], 16),
            set_count=tuple(str(len(f)) for f in sets),
            set_funcs=_wrap([str(f) for fs in sets for f in fs + [0] * (width - len(fs))], 16),
            set_width=width,
            index_type="unsigned char"
            if max(len(sets), len(pc.functions)) <= 255
            else "unsigned short",
        )
    return PolySpec(
        n_funcs=len(pc.functions),
        pieces=p_max,
        level_a=tuple(level_a),
        level_b=tuple(level_b),
        sign=tuple(sign),
        starts=wrap(starts),
        inv_width=wrap(inv_w),
        area=wrap(area),
        moment=wrap(moment),
        low=lit(pc.low),
        width=lit(pc.width),
        **firing,  # type: ignore[arg-type]
    )


def _output(
    rb: RuleBase,
    k: int,
    out: Variable,
    lit: _Lit,
    agg_fmt: dict[str, str],
    wrap: Callable[[list[str]], tuple[str, ...]],
    grid: dict[tuple[int, int], Rule] | None,
    windows: bool,
    sugeno_lit: _Lit,
) -> ExactOutput:
    if out.is_sugeno:
        return _sugeno_output(rb, k, out, lit, sugeno_lit)
    pieces = OutputPieces(rb, out)
    ops = rb.operators
    rules_of_term: dict[int, list[int]] = {}
    for r, rule in enumerate(rb.rules):
        for c in rule.consequents:
            if c.variable == out.name:
                rules_of_term.setdefault(out.term_index(c.term), []).append(r)
    zero = lit(0.0)
    grid_cons: tuple[str, ...] = ()
    cons: list[int] = []
    if grid is not None:
        # one padding row and column of "no rule" for the window's neighbour past the end
        t0, t1 = len(rb.inputs[0].terms) + 1, len(rb.inputs[1].terms) + 1
        cons = [len(out.terms)] * (t0 * t1)
        for (i, j), rule in grid.items():
            for c in rule.consequents:
                if c.variable == out.name:
                    cons[i * t1 + j] = out.term_index(c.term)
        grid_cons = _wrap([str(c) for c in cons], 16)
    empty_geo = dict(
        n_intervals=0, slots=0, z=(), slot_piece=(), slope=(), anchor=(), candidates=0, points=0,
        gl_nodes=(), gl_weights=(),
    )  # fmt: skip
    if rb.defuzzifier == "weighted_average":
        fmt = {
            "max": agg_fmt["max"],
            "bounded_sum": "{a} + {b}",
            "probabilistic_sum": agg_fmt["psum"],
        }
        acts = []
        for t in range(len(out.terms)):
            items = [f"w[{r}]" for r in rules_of_term.get(t, [])]
            a = _fold(items, fmt[ops.aggregation], zero)
            if ops.aggregation == "bounded_sum" and len(items) > 1:
                a = agg_fmt["min"].format(a=a, b=lit(1.0))
            acts.append(a)
        centres = tuple(lit(membership.centre(t, out.low, out.high)) for t in out.terms)
        return ExactOutput(
            index=k, name=out.name, low=lit(out.low), high=lit(out.high),
            default=lit.maybe_nan(out.default), defuzzifier=rb.defuzzifier,
            n_pieces=len(out.terms), level_exprs=tuple(acts), centres=centres,
            empty=pieces.empty, grid_cons=grid_cons, **empty_geo,  # type: ignore[arg-type]
        )  # fmt: skip
    if pieces.empty:
        return ExactOutput(
            index=k, name=out.name, low=lit(out.low), high=lit(out.high),
            default=lit.maybe_nan(out.default), defuzzifier=rb.defuzzifier, n_pieces=0,
            level_exprs=(), centres=(), empty=True, **empty_geo,  # type: ignore[arg-type]
        )  # fmt: skip
    if pieces.per_term:
        level_fmt = agg_fmt["max"] if ops.aggregation == "max" else "{a} + {b}"
        levels = tuple(
            _fold([f"w[{r}]" for r in rules_of_term.get(t, [])], level_fmt, zero)
            for t in range(len(out.terms))
        )
    else:
        levels = tuple(f"w[{int(r)}]" for r in pieces.inst_rules)

    def closed_form(**how: PolySpec | GaussSpec | QuadSpec) -> ExactOutput:
        """An output integrated in closed form from its levels: no breakpoint sweep."""
        return ExactOutput(
            index=k, name=out.name, low=lit(out.low), high=lit(out.high),
            default=lit.maybe_nan(out.default), defuzzifier=rb.defuzzifier,
            n_pieces=pieces.n_pieces, level_exprs=levels, centres=(), empty=False,
            grid_cons=grid_cons, **how, **empty_geo,  # type: ignore[arg-type]
        )  # fmt: skip

    qrule = _quadrature_rule(rb, out)
    if qrule is not None:
        table = [lit(float(v)) for v in terms_at_nodes(qrule, out, pieces).ravel()]
        quad = QuadSpec(
            n_nodes=len(qrule.nodes),
            nodes=wrap([lit(float(v)) for v in qrule.nodes]),
            weights=wrap([lit(float(v)) for v in qrule.weights]),
            table=wrap(table),
            cells=qrule.cells,
            per_cell=qrule.per_cell,
            bound=qrule.bound,
        )
        return closed_form(quad=quad)
    if _gaussian_closed_form(rb, out):
        gg = GaussianGeometry(rb, out, pieces)
        k_ = gg.k
        n_points = 2 + len(gg.fixed) + (k_ * (k_ - 1) if gg.product else 2 * k_ * k_)
        pairs: list[tuple[int, int, str, str, str]] = []
        linear: list[bool] = []
        for i, j in itertools.combinations(range(k_), 2):
            qa, qb, qc = quadratic(gg.m[i], gg.s[i], gg.m[j], gg.s[j])
            pairs.append((i, j, lit(qa), lit(qb), lit(qc)))
            linear.append(qa == 0.0)
        gauss = GaussSpec(
            means=tuple(lit(float(v)) for v in gg.m),
            sigmas=tuple(lit(float(v)) for v in gg.s),
            fixed=tuple(lit(float(v)) for v in gg.fixed),
            n_points=n_points,
            product=gg.product,
            pairs=tuple(pairs) if gg.product else (),
            linear=tuple(linear) if gg.product else (),
            sqrt2=lit(math.sqrt(2.0)),
            sqrt_half_pi=lit(math.sqrt(0.5 * math.pi)),
            peaks=tuple(lit(float(v)) for v in gg.peak),
            gpeaks=tuple(
                lit(float(np.exp(-0.5 * ((p - m) / sg) ** 2)))
                for p, m, sg in zip(gg.peak, gg.m, gg.s, strict=True)
            ),
            keep=lit(1.0 - TIE),
        )
        return closed_form(gauss=gauss)
    geo = PiecewiseLinearGeometry(rb, out, pieces)
    # the engine's fast centroid where the target's templates take it, else the general sweep
    firing_cons = cons if windows else None
    poly = _poly(rb, out, pieces, geo, lit, wrap, firing_cons) if lit.target.fast_centroid else None
    if poly is not None:
        return closed_form(poly=poly)
    m, kmax = len(geo.z0), geo.kmax
    if ops.implication == "min" and ops.aggregation == "max":
        cand = kmax * kmax
    elif ops.implication == "min":
        cand = kmax
    elif ops.aggregation == "max":
        cand = kmax * (kmax - 1) // 2
    else:
        cand = 0
    base = 2 + cand
    points = 2 * base - 1 if ops.aggregation == "bounded_sum" else base
    xg, wg = geo.gl
    z = [*geo.z0.tolist(), float(geo.z1[-1])]
    return ExactOutput(
        index=k,
        name=out.name,
        low=lit(out.low),
        high=lit(out.high),
        default=lit.maybe_nan(out.default),
        defuzzifier=rb.defuzzifier,
        n_pieces=pieces.n_pieces,
        level_exprs=levels,
        centres=(),
        n_intervals=m,
        slots=kmax,
        z=wrap([lit(v) for v in z]),
        slot_piece=_wrap([str(int(p)) for p in geo.slot_piece.ravel()], 16),
        slope=wrap([lit(float(v)) for v in geo.slope.ravel()]),
        anchor=wrap(
            [lit(float(v)) for v in np.where(geo.slope != 0.0, geo.root, geo.icpt).ravel()]
        ),
        candidates=cand,
        points=points,
        gl_nodes=tuple(lit(float(v)) for v in xg) if ops.aggregation == "probabilistic_sum" else (),
        gl_weights=tuple(lit(float(v)) for v in wg)
        if ops.aggregation == "probabilistic_sum"
        else (),
        empty=False,
        grid_cons=grid_cons,
    )


def _sugeno_output(rb: RuleBase, k: int, out: Variable, lit: _Lit, value_lit: _Lit) -> ExactOutput:
    """A Sugeno output: its consequents in rule order (``fuzzkit.fuzzy.sugeno.SugenoOutput``),
    their coefficients as literals of the Sugeno stage's type (``value_lit``)."""
    n = len(rb.inputs)
    cons = []
    for r, rule in enumerate(rb.rules):
        for c in rule.consequents:
            if c.variable != out.name:
                continue
            term = out.term(c.term)
            coefs = (0.0,) * n if term.shape == "constant" else tuple(term.params[:n])
            const = term.params[0] if term.shape == "constant" else term.params[n]
            nonzero = tuple((i, value_lit(v)) for i, v in enumerate(coefs) if v != 0.0)
            cons.append(SugenoTerm(r, nonzero, value_lit(const)))
    return ExactOutput(
        index=k, name=out.name, low=lit(out.low), high=lit(out.high),
        default=lit.maybe_nan(out.default), defuzzifier=rb.defuzzifier, n_pieces=0,
        level_exprs=(), centres=(), empty=not cons, sugeno=tuple(cons), n_intervals=0, slots=0,
        z=(), slot_piece=(), slope=(), anchor=(), candidates=0, points=0, gl_nodes=(),
        gl_weights=(),
    )  # fmt: skip


def _bound_note(number_type: str, target: Target) -> str:
    eps = "2^-52" if number_type == "double" else "2^-23"
    what = target.runtime[number_type]
    return (
        f"Exact inference in {what}: the only error against fuzzkit's exact engine is rounding, "
        f"at most {ROUNDING_ULPS} x {eps} x the output's full scale (largest |range end|) for "
        "centroid, bisector and weighted average. mean/smallest/largest of maximum jump where "
        "two maxima tie; there a rounding difference can pick the other one."
    )


def _quad_note(outputs: tuple[ExactOutput, ...]) -> str:
    """The proven quadrature bound of each output integrated by one (codegen.smooth_quadrature:
    Gaussian terms, product implication, probabilistic sum, centroid)."""
    return "".join(
        f" Output {o.name!r} (Gaussian terms under a probabilistic sum) is integrated by "
        f"{o.quad.cells} x {o.quad.per_cell}-node Gauss-Legendre on the whole range, its "
        f"aggregated set being analytic: the quadrature's own centroid error is proven at most "
        f"{o.quad.bound:.2e} (Bernstein-ellipse bound, whatever the firing strengths), on top "
        "of the rounding."
        for o in outputs
        if o.quad is not None
    )


def _wide_note(wide: bool) -> str:
    if not wide:
        return ""
    return (
        " The Sugeno stage is computed in double (linear terms over inputs that are not "
        "clamped see them up to 1e100, as the engine does) and rounded once to float: a value "
        "beyond float's range comes out as +-inf."
    )


def build_exact_spec(
    rb: RuleBase,
    target: str,
    number_type: str = "double",
    *,
    fpi_defaults: FpiDefaults | None = None,
) -> ExactSpec:
    """Collect, check and format everything the exact-method templates need.

    Raises
    ------
    CodegenError
        Unknown target, a name that cannot be an identifier, a Q15 type, or output terms the
        method cannot integrate (see :func:`unsupported_reason`).
    """
    from fuzzkit import __version__

    tg = load_target(target)
    tg.check_number_type(number_type, f"--type {number_type}")
    why = unsupported_reason(rb, number_type)
    if why is not None:
        raise CodegenError(f"rule base {rb.name!r}: --method exact: {why}")
    # only the rule base's name is an identifier in the code (keywords mangled); variable
    # names are strings and comments there, so they need only be identifiers, keywords too
    name = check_module_name(check_identifier(symbol(rb.name), "rule base name"))
    for var in rb.inputs + rb.outputs:
        check_name(var.name, f"variable name ({rb.name})")
    lit = _Lit(tg, number_type)
    per_line = tg.values_per_line["exact"]

    def wrap(items: list[str]) -> tuple[str, ...]:
        return _wrap(items, per_line)

    vertical = 1e200 if number_type == "double" else 1e30
    inputs = []
    mu_index: dict[tuple[str, str], int] = {}
    offset = 0
    for i, var in enumerate(rb.inputs):
        for j, term in enumerate(var.terms):
            mu_index[(var.name, term.name)] = offset + j
        inputs.append(
            ExactInput(
                i, var.name, lit(var.low), lit(var.high), _input_terms(var, offset, lit, vertical)
            )
        )
        offset += len(var.terms)
    ops = rb.operators
    callee = {h: f.format(name=name) for h, f in tg.functions.items()}
    agg_fmt = {h: callee[h] + "({a}, {b})" for h in ("min", "max", "psum")}
    agg_fmt["product"] = "{a} * {b}"
    expr_ops = {
        "and": agg_fmt["min"] if ops.and_ == "min" else agg_fmt["product"],
        "or": agg_fmt["max"] if ops.or_ == "max" else agg_fmt["psum"],
        "one": lit(1.0),
    }
    weights = [r.weight for r in rb.rules]
    any_weight = any(w != 1.0 for w in weights)
    rules = []
    for r, rule in enumerate(rb.rules):
        expr = _expression(rule.antecedent, rb, mu_index, expr_ops)
        if any_weight:
            expr = f"({expr}) * {lit(rule.weight)}"
        rules.append(ExactRule(r, _comment_safe(_rule_text(rule.antecedent)), expr))
    grid = grid_rules(rb) if tg.visits_firing_cells else None
    windows = _windows(rb, lit) if grid is not None else None
    wide = wide_sugeno(rb, number_type)
    sugeno_lit = _Lit(tg, "double") if wide else lit
    outputs = tuple(
        _output(rb, k, out, lit, agg_fmt, wrap, grid, windows is not None, sugeno_lit)
        for k, out in enumerate(rb.outputs)
    )
    libm: set[str] = set()
    for var in rb.inputs:
        for term in var.terms:
            form = _exact_form(term)
            libm.update(form.libm if form is not None else ())
    if rb.defuzzifier == "bisector" and ops.aggregation != "probabilistic_sum":
        libm.add("sqrt")
    for o in outputs:
        if o.gauss is None:
            continue
        libm.update(("log", "sqrt"))  # where a term meets a level: m -+ s sqrt(-2 ln L)
        if o.defuzzifier in ("centroid", "bisector"):  # the integrals: erfc and exp
            libm.update(("erfc", "exp", "fabs"))
            if o.gauss.product:
                libm.add("copysign")
    own_math = libm & set(tg.portable_math.get(number_type, ()))
    if "pow" in own_math:
        own_math.update(("exp", "log"))  # pow is computed as exp(b log a)
    if "erfc" in own_math:
        own_math.add("exp")  # erfc is computed through exp
    libm -= own_math
    has_fpi = len(rb.inputs) == 2
    note = (
        ""
        if has_fpi
        else "no fuzzy-PI API: it needs exactly 2 inputs (e, de), this rule base has "
        f"{len(rb.inputs)}"
    )
    defaults = None
    if fpi_defaults is not None and has_fpi:
        gains = {k: float(getattr(fpi_defaults, k)) for k in FPI_GAIN_KEYS}
        if number_type == "float":
            _check_float32_gains(gains, fpi_defaults.source)
        defaults = {k: lit(v) for k, v in gains.items()}
    file_name, sha = source_sha256(rb)
    desc = tuple(textwrap.wrap(_comment_safe(" ".join(rb.description.split())), 88)[:8])
    real_bytes = 8 if number_type == "double" else 4
    stack = real_bytes * (
        offset
        + len(rb.rules)
        + max((o.n_pieces + 1 + 4 * o.n_intervals * max(o.points, 1) for o in outputs), default=0)
    )
    # with grid rules the expressions are not emitted (the loop inlines its operators)
    code = (
        ""
        if grid is not None
        else " ".join([r.expr for r in rules] + [e for o in outputs for e in o.level_exprs])
    )
    helpers = {h for h in ("min", "max", "psum") if f"{callee[h]}(" in code}
    helpers.update(
        KIND_HELPERS[t.kind] for ax in inputs for t in ax.terms if t.kind in KIND_HELPERS
    )
    if any(o.gauss is not None and o.gauss.product for o in outputs):
        helpers.add("finite")  # the crossings of two scaled Gaussians may not exist
    geo = [o for o in outputs if o.n_intervals]
    if (ops.implication == "product" and ops.aggregation == "max" and geo) or (
        rb.defuzzifier == "bisector" and ops.aggregation != "probabilistic_sum" and geo
    ):
        helpers.add("finite")
    max_base = max((2 + o.candidates for o in geo), default=0)
    max_pieces = max((o.n_pieces for o in geo), default=0)
    return ExactSpec(
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
        description=desc,
        n_inputs=len(rb.inputs),
        n_outputs=len(rb.outputs),
        n_mu=offset,
        n_rules=len(rb.rules),
        inputs=tuple(inputs),
        rules=tuple(rules),
        outputs=outputs,
        implication=ops.implication,
        aggregation=ops.aggregation,
        clamp=rb.out_of_range == "clamp",
        units_line=units_line(rb),
        input_units=tuple(units_comment(v.units) for v in rb.inputs),
        output_units=tuple(units_comment(v.units) for v in rb.outputs),
        libm=tuple(sorted(libm)),
        own_math=tuple(sorted(own_math)),
        bound_note=tuple(
            textwrap.wrap(_bound_note(number_type, tg) + _wide_note(wide) + _quad_note(outputs), 88)
        ),
        has_fpi=has_fpi,
        fpi_note=note,
        fpi_defaults=defaults,
        zero=lit(0.0),
        one=lit(1.0),
        half=lit(0.5),
        # values this close to the height (a share of it) are one maximum: the engine's TIE in
        # double; float rounding of equal levels reaches a few float ulps
        tie=lit(TIE) if number_type == "double" else lit(2.0**-20),
        tiny=lit(1e-300) if number_type == "double" else lit(0.0),
        bisect_margin=lit(1.0 - 1e-15) if number_type == "double" else lit(1.0),
        extend_limit=lit(membership.EXTEND_LIMIT) if number_type == "double" else lit(1e30),
        vertical=lit(vertical),
        stack_bytes=stack,
        helpers=tuple(sorted(helpers)),
        has_geometry=bool(geo),
        max_base=max_base,
        piece_type="unsigned char" if max_pieces < 255 else "unsigned short",
        two=lit(2.0),
        line_nodes=(lit(float(LINEAR_NODES[0][0])), lit(float(LINEAR_NODES[0][1]))),
        line_weights=(lit(float(LINEAR_NODES[1][0])), lit(float(LINEAR_NODES[1][1]))),
        and_=ops.and_,
        or_=ops.or_,
        weighted=any_weight,
        grid=grid is not None,
        grid_weights=()
        if grid is None or not any_weight
        else wrap(
            [
                lit(grid[(i, j)].weight if (i, j) in grid else 0.0)
                for i in range(len(rb.inputs[0].terms) + 1)
                for j in range(len(rb.inputs[1].terms) + 1)
            ]
        ),
        n_terms0=len(rb.inputs[0].terms),
        n_terms1=len(rb.inputs[1].terms) if len(rb.inputs) > 1 else 0,
        windows=windows or (),
        keeps_inputs=any(any(t.coefficients) for o in outputs for t in o.sugeno),
        sugeno_type=tg.type_names["double" if wide else number_type],
        sugeno_wide=wide,
        sugeno_extend_limit=sugeno_lit(membership.EXTEND_LIMIT) if wide else "",
    )


def emit_exact(
    rb: RuleBase,
    target: str,
    number_type: str = "double",
    *,
    fpi_defaults: FpiDefaults | None = None,
) -> dict[str, str]:
    """Generate the exact-method ``target`` sources for ``rb``: ``{relative path: text}``
    (an interval type-2 rule base's by :mod:`fuzzkit.codegen.exact_type2`)."""
    if isinstance(rb, Type2RuleBase):
        from fuzzkit.codegen.exact_type2 import emit_exact_type2

        if fpi_defaults is not None:
            raise CodegenError(
                f"rule base {rb.name!r}: --gains is not baked into interval type-2 exact code "
                "yet (pass the gains to NAME_fpi_init)"
            )
        return emit_exact_type2(rb, target, number_type)
    spec = build_exact_spec(rb, target, number_type, fpi_defaults=fpi_defaults)
    return render_files(target, spec.name, spec, "exact")


def rounding_allowance(rb: RuleBase, number_type: str) -> tuple[float, ...]:
    """The stated rounding bound of each output in output units."""
    eps = ROUNDING_BOUND[number_type]
    return tuple(eps * max(abs(v.low), abs(v.high)) for v in rb.outputs)


__all__ = [
    "DISCONTINUOUS",
    "EXACT_NUMBER_TYPES",
    "NOT_YET",
    "ROUNDING_BOUND",
    "ExactSpec",
    "build_exact_spec",
    "emit_exact",
    "not_yet",
    "rounding_allowance",
    "unsupported_reason",
]
