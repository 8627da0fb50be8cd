"""The whole outer-loop controller as C or Python: the controller artefact.

:func:`build_controller_spec` turns a :class:`ControllerDesign` (the controller spec as plain
data: ``fuzzkit.codegen`` reads the fuzzy model only, so ``fuzzkit.loop.controller_code``
converts ``fuzzkit.control.spec.ControllerSpec`` into it) into the one object the
``backends/<target>/controller.*.jinja`` templates see, :class:`ControllerCodeSpec`. The
controller is the reference's logic (``fuzzkit.control.controllers.HybridForceController``
with its ``FrontEnd``, ``docs/controller.md``) operation for operation: missing samples, tare,
gravity compensation, spike gate, trip and back-off, low-pass, debounced engagement, and per
axis the incremental PI or fuzzy-PI with its ``|du|`` and ``|u|`` limits.

A fuzzy-PI's surface is the rule base compiled by the exact method (``exact.py``): rounding
error only (at most ``exact.ROUNDING_BOUND`` x the output's full scale x ``kx``, about 1e-17 m
in double), where a lookup table's bound (1e-3 of the range by default, 2e-7 m at
``kx = 2e-4``) would not let the generated controller equal the reference to 1e-9 m. C: the
surface is a sibling unit, ``NAME_surface.{h,c}`` (its symbols prefixed ``NAME_surface_``, so
two controllers on one rule base link together); Python: embedded in ``NAME_controller.py``.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import itertools
import math
import textwrap
import uuid
from collections.abc import Callable
from dataclasses import dataclass

from fuzzkit.codegen.emit import (
    TableSpec,
    _check_float32_gains,
    _comment_safe,
    build_spec,
    check_identifier,
    check_module_name,
    render_files,
)
from fuzzkit.codegen.exact import ROUNDING_BOUND, ExactSpec, build_exact_spec
from fuzzkit.codegen.exact_type2 import Type2Spec, build_type2_spec
from fuzzkit.codegen.lookup_table import LookupTable
from fuzzkit.codegen.table_search import make_table
from fuzzkit.codegen.target import load_target
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.type2_model import Type2RuleBase

KINDS = ("pi", "fuzzy-pi")
AXES = ("x", "y", "z")
#: The status bits the templates set (the design gives their values and meaning).
STATUS_USED = ("ENGAGED", "HELD", "TRIPPED", "RETREATING", "SATURATED", "TARING", "REJECTED")


@dataclass(frozen=True)
class StatusBit:
    """One bit of the status a step returns: its name, value and what it means."""

    name: str
    value: int
    doc: str


@dataclass(frozen=True)
class AdaptationDesign:
    """The spec's adaptation as plain data (``fuzzkit.control.adaptation_spec``, whose
    arithmetic ``fuzzkit.control.adaptation`` the templates repeat operation for operation).

    ``mode``: ``stiffness-scheduled`` or ``self-tuning``. Schedule: the estimator's ``window``
    and ``delay`` (periods), ``forgetting``, the excitation thresholds ``min_step_m`` and
    ``min_force_n``, the initial estimate and its bounds (N/mm), the bands as ``(up_to_n_mm or
    None, scale)``, the dwell time in periods, the sudden-stiffening factor ``jump`` and the
    least ``spread`` of the increments the slope needs, the force ``contact_n`` (N) both ends of
    the window must reach for an update (out of contact the estimate is frozen). Self-tuning:
    ``alpha_min``, ``alpha_max``, the rule table of alpha (7x7, rows e, columns de) and the input
    gains per axis. The inner-loop model the estimator regresses on: ``inner_q``, ``inner_a``,
    ``inner_g``. Safe start: the band until the estimate is trusted (``safe_band``, the one of
    ``k_max``), the most conservative band (``floor_band``, for a contact stiffer than
    ``k_max``), the updates that make the estimate trusted (``trust_updates``) and the
    secant's span, in excitation thresholds, that does too (``trust_span``). ``inverse_n_mm``:
    the 1/k schedule's constant instead of bands (factor ``min(1, inverse_n_mm / k)``).
    """

    mode: str
    window: int = 1
    delay: int = 1
    forgetting: float = 1.0
    min_step_m: float = 0.0
    min_force_n: float = 0.0
    initial_n_mm: float = 1.0
    k_min_n_mm: float = 0.0
    k_max_n_mm: float = 1.0
    bands: tuple[tuple[float | None, float], ...] = ()
    dwell_periods: int = 1
    alpha_min: float = 0.0
    alpha_max: float = 1.0
    alpha_table: tuple[tuple[float, ...], ...] = ()
    ge: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gde: tuple[float, float, float] = (0.0, 0.0, 0.0)
    jump: float = 4.0
    spread: float = 0.05
    contact_n: float = 1.0
    inner_q: float = 0.0
    inner_a: float = 0.0
    inner_g: float = 1.0
    safe_band: int = 0
    floor_band: int = 0
    trust_updates: int = 4
    trust_span: float = 2.0
    inverse_n_mm: float | None = None


@dataclass(frozen=True)
class AdaptationCode:
    """The adaptation as the templates write it (literals formatted)."""

    mode: str
    scheduled: bool
    history: int  # window + delay: the ring's length
    window: int
    delay: int
    forgetting: str
    min_step: str
    min_force: str
    initial: str
    k_min: str
    k_max: str
    band_limits: tuple[str, ...]  # every band's up_to but the last's
    band_scales: tuple[str, ...]
    safe_band: int  # until the estimate is trusted, and at the start
    floor_band: int  # a contact stiffer than k_max
    trust: int  # updates until the estimate is trusted
    trust_step: str  # the secant's least span: trust_span * min_step_m, * min_force_n
    trust_force: str
    inverse: str | None  # the 1/k schedule's constant (N/mm), instead of bands
    dwell: int
    alpha_low: str
    alpha_span: str
    alpha_table: tuple[tuple[str, ...], ...]
    ge: tuple[str, str, str]
    gde: tuple[str, str, str]
    thousand: str
    three: str
    jump: str
    spread: str
    contact: str  # the least force (N) at both ends of the window for an update
    inner_q: str  # x = q*x + (1-q)*u; m = a*m + ((1-a)*g)*x, the literals as the reference rounds
    inner_q1: str
    inner_a: str
    inner_ag: str


@dataclass(frozen=True)
class ControllerDesign:
    """A controller spec as plain data: everything the generated controller bakes in.

    Per-axis tuples are in x, y, z order; an axis that is not force controlled
    (``selection[i]`` False) has set point and gains 0. ``engage_threshold_n`` None: engaged
    from the start. ``mass_kg`` None: no gravity compensation (no rotation needed).
    ``lowpass_alpha`` 1: no filter. ``spike_gate_n`` is the resolved gate (N).
    """

    name: str
    kind: str
    period_s: float
    selection: tuple[bool, bool, bool]
    setpoints_n: tuple[float, float, float]
    kp: tuple[float, float, float]
    ki: tuple[float, float, float]
    kx: tuple[float, float, float]
    correction_m: float
    step_m: float
    limit_n: float
    engage_threshold_n: float | None
    engage_samples: int
    spike_gate_n: float
    spike_confirm: int
    trip_samples: int
    backoff_m: float
    backoff_speed_m_s: float
    tare_samples: int
    mass_kg: float | None
    gravity_m_s2: float
    lowpass_alpha: float
    rulebase: RuleBase | None
    status_bits: tuple[StatusBit, ...]
    description: str = ""
    source_file: str = "<spec>"
    source_sha256: str = ""
    adaptation: AdaptationDesign | None = None
    #: how the fuzzy-PI evaluates its surface: ``exact`` or ``table`` (sized by exactly one of
    #: ``surface_tolerance``, a fraction of the output's range, or ``surface_resolution``)
    surface_method: str = "exact"
    surface_tolerance: float | None = None
    surface_resolution: int | None = None


@dataclass(frozen=True)
class ControllerAxis:
    """One task axis as the templates need it (literals already formatted)."""

    index: int
    name: str
    selected: bool
    setpoint: str
    setpoint_text: str  # for comments: 6 significant digits
    kp: str
    ki: str
    kx: str


@dataclass(frozen=True)
class StatusSpec:
    """A status bit as the templates write it: constant name suffix, value, comment lines."""

    name: str
    value: int
    shift: int
    doc: tuple[str, ...]


@dataclass(frozen=True)
class ControllerCodeSpec:
    """Everything a controller template may use; nothing else reaches the generated text."""

    name: str
    upper: str
    module: str  # NAME_controller: file stem and symbol prefix
    surface_name: str  # NAME_surface: the fuzzy-PI surface's file stem and prefix ("" for PI)
    target: str
    number_type: str
    ctype: str
    fsuffix: str
    version: str
    source_file: str
    source_sha256: str
    description: tuple[str, ...]
    kind: str
    fuzzy: bool
    axes: tuple[ControllerAxis, ...]
    selected: tuple[int, ...]
    period: str
    correction: str
    step: str
    limit: str
    #: the same for comments: 6 significant digits
    period_text: str
    correction_text: str
    step_text: str
    limit_text: str
    engage_at_start: bool
    engage_threshold: str
    engage_samples: int
    spike_gate: str
    spike_confirm: int
    trip_samples: int
    backoff: str
    backoff_step: str
    tare_samples: int
    has_tool: bool
    weight: str  # m * g (N)
    has_filter: bool
    alpha: str
    zero: str
    one: str
    status: tuple[StatusSpec, ...]
    libm: tuple[str, ...]
    #: the surface: an exact-method spec, or a lookup table's for a table surface (Python
    #: embeds it; C renders it as a sibling unit)
    surface: ExactSpec | TableSpec | Type2Spec | None
    #: the file kind the surface renders as: ``surface`` (exact) or ``surface_table``
    surface_kind: str
    float_bound_note: tuple[str, ...]
    #: a stable identifier of this generated controller (same spec, fuzzkit version and
    #: number type -> same value): the FMU's ``guid``
    guid: str
    #: the online adaptation of the output gain (None: fixed gains)
    adapt: AdaptationCode | None = None
    #: gains, set points and safety limit live in the state (``Target.tunable_parameters``)
    tunable: bool = False


def float_step_bound(design: ControllerDesign, force_bound_n: float) -> float:
    """The most one period's float rounding moves the correction away from the double one (m).

    While both builds take the same decisions (engagement, gate, trip, limits), ``u`` of the
    float build drifts from the double one by rounding alone: per period the ``u + du``
    addition and clamp (``2 eps |u|``, ``|u| <= correction_m``), ``du`` itself (``4 eps
    step_m``), the error of ``e`` carried through the gains (``e`` from float sums of forces up
    to ``force_bound_n``: ``8 eps force_bound_n`` for ``e``, twice that for ``de``) and, for a
    fuzzy-PI, the float surface's own rounding (``exact.ROUNDING_BOUND`` x the output's full
    scale x ``kx``) and its slope (at most ``slope_bound`` of the rule base's output per unit
    input, times the input errors). ``eps = 2^-23``; a 2x margin on the whole.
    """
    eps = 2.0**-23
    per_axis = []
    for i in range(3):
        if not design.selection[i]:
            continue
        de_err = 16.0 * eps * force_bound_n
        e_err = 8.0 * eps * force_bound_n
        if design.kind == "pi":
            gain = design.kp[i] * de_err + design.ki[i] * e_err
        else:
            rb = design.rulebase
            if rb is None:  # pragma: no cover - a fuzzy-PI design always has its rule base
                raise CodegenError("a fuzzy-PI design needs its rule base")
            full = max(abs(rb.outputs[0].low), abs(rb.outputs[0].high))
            slope = slope_bound(rb)
            inputs = design.ki[i] * e_err + design.kp[i] * de_err + 4.0 * eps
            gain = design.kx[i] * (ROUNDING_BOUND["float"] * full + slope * inputs)
        per_axis.append(2.0 * eps * design.correction_m + 4.0 * eps * design.step_m + gain)
    return 2.0 * max(per_axis, default=0.0)


def slope_bound(rb: RuleBase) -> float:
    """An upper bound of the surface's slope per unit input (output units), for the float note.

    The steepest possible change of a defuzzified output across one elementary interval of the
    inputs is its full output range over the narrowest distance between two term vertices of
    an input; summed over the two inputs.
    """
    total = 0.0
    out = rb.outputs[0]
    span = out.high - out.low
    for var in rb.inputs[:2]:
        points = sorted({float(p) for t in var.terms for p in t.params} | {var.low, var.high})
        gaps = [b - a for a, b in itertools.pairwise(points) if b - a > 0.0]
        total += span / min(gaps)
    return total


def _float_note(design: ControllerDesign, number_type: str) -> str:
    if number_type == "float" and design.adaptation is not None:
        return (
            "float (for single-precision FPUs): with adaptation no bound on the distance from "
            "the double build is stated (the stiffness estimate's band and alpha depend on "
            "rounding); the double build is the one tested equal to the reference."
        )
    if number_type == "double":
        return (
            "double: equal to fuzzkit's reference controller (fuzzkit.control) to 1e-9 m per "
            "sample, with the same status, on random and hostile sensor logs (tested)."
        )
    force = 1000.0
    return (
        "float (for single-precision FPUs): while it takes the same decisions as the double "
        f"build, |u_float - u_double| grows by at most {float_step_bound(design, force):.3g} m "
        f"per period with |force| <= {force:g} N, i.e. after n periods at most n times that "
        "(tested against the reference on random and hostile logs); a sample within float "
        "rounding of a threshold (engagement, spike gate, safety limit) may be decided "
        "differently."
    )


def controller_files(design: ControllerDesign) -> tuple[str, str]:
    """The checked stems ``(NAME_controller, NAME_surface)`` of the generated files."""
    name = check_identifier(design.name, "controller name")
    return (
        check_module_name(f"{name}_controller", "controller"),
        check_module_name(f"{name}_surface", "controller"),
    )


def _surface_rulebase(design: ControllerDesign, surface_name: str) -> RuleBase:
    rb = design.rulebase
    if rb is None:
        raise CodegenError(f"controller {design.name!r}: a fuzzy-PI needs its rule base")
    if len(rb.inputs) != 2 or not rb.outputs:
        raise CodegenError(
            f"controller {design.name!r}: rule base {rb.name!r} must have 2 inputs (e, de) "
            f"and an output (has {len(rb.inputs)} inputs, {len(rb.outputs)} outputs)"
        )
    return dataclasses.replace(rb, name=surface_name)


@functools.lru_cache(maxsize=16)
def surface_table(
    rb: RuleBase, tolerance: float | None, resolution: int | None, what: str = "controller"
) -> LookupTable:
    """The double lookup table of a ``table`` surface, found as ``fuzzkit compile --method
    table`` finds it: the smallest whose verified bound meets ``tolerance`` (a fraction of the
    output's range), or the one of ``resolution`` breakpoints per input. The generated
    controller and the reference (``fuzzkit.loop.controller_code.spec_surface``) both
    evaluate this table.

    Raises
    ------
    CodegenError
        Not exactly one of ``tolerance`` and ``resolution``, or a tolerance no table meets.
    Built once per process for an equal rule base and size (the table is frozen): an IT2
    rule base's 65 x 65 table is about 2 s of engine time, and the generated controller and
    the reference each ask for it.
    """
    if (tolerance is None) == (resolution is None):
        raise CodegenError(f"{what}: a table surface needs exactly one of tolerance or resolution")
    return make_table(rb, number_type="double", tolerance=tolerance, resolution=resolution)


def _guid(design: ControllerDesign, number_type: str, version: str) -> str:
    """FMI's ``{8-4-4-4-12}`` identifier of what is generated: a hash of every input to it."""
    content = f"fuzzkit {version} {number_type} {design!r}"
    return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, content)) + "}"


def build_controller_spec(
    design: ControllerDesign, target: str, number_type: str | None = None
) -> ControllerCodeSpec:
    """Collect, check and format everything the controller templates of ``target`` need.

    Raises
    ------
    CodegenError
        Unknown target or kind, a number type the target does not compute in, a name that
        cannot be an identifier, a fuzzy-PI without a 2-input rule base the exact method
        compiles, or parameters a C float cannot hold.
    """
    from fuzzkit import __version__

    tg = load_target(target)
    nt = number_type or tg.default_number_type
    tg.check_number_type(nt, f"--type {nt}")
    if nt not in ("float", "double"):
        raise CodegenError(f"the controller computes in float or double; got --type {nt}")
    if design.kind not in KINDS:
        raise CodegenError(f"unknown controller kind {design.kind!r} (expected pi or fuzzy-pi)")
    module, surface_name = controller_files(design)
    name = design.name
    fuzzy = design.kind == "fuzzy-pi"
    surface: ExactSpec | TableSpec | Type2Spec | None = None
    if fuzzy:
        srb = _surface_rulebase(design, surface_name)
        if design.surface_method == "table":
            if nt != "double":
                raise CodegenError(
                    f"controller {name!r}: a table surface's controller computes in double "
                    f"(got --type {nt})"
                )
            what = f"controller {name!r}"
            table = surface_table(srb, design.surface_tolerance, design.surface_resolution, what)
            surface = build_spec(srb, table, target)
        elif isinstance(srb, Type2RuleBase):
            surface = build_type2_spec(srb, target, nt)
        else:
            surface = build_exact_spec(srb, target, nt)
    weight = 0.0 if design.mass_kg is None else design.mass_kg * design.gravity_m_s2
    backoff_step = design.backoff_speed_m_s * design.period_s
    values = {
        "correction_m": design.correction_m,
        "step_m": design.step_m,
        "limit_n": design.limit_n,
        "spike_gate_n": design.spike_gate_n,
        "backoff_m": design.backoff_m,
        "backoff step": backoff_step,
        "m*g": weight,
        "lowpass alpha": design.lowpass_alpha,
    }
    for i, axis in enumerate(AXES):
        if design.selection[i]:
            values.update(
                {f"{axis}.kp": design.kp[i], f"{axis}.ki": design.ki[i]}
                | ({f"{axis}.kx": design.kx[i]} if fuzzy else {})
            )
    if design.engage_threshold_n is not None:
        values["engage threshold_n"] = design.engage_threshold_n
    bad = [k for k, v in values.items() if not math.isfinite(v)]
    if bad:
        raise CodegenError(f"controller {name!r}: {', '.join(bad)} must be finite")
    if nt == "float":
        _check_float32_gains({k: v for k, v in values.items() if v != 0.0}, f"controller {name}")

    def lit(v: float) -> str:
        return tg.literal(v, nt)

    axes = tuple(
        ControllerAxis(
            index=i,
            name=axis,
            selected=design.selection[i],
            setpoint=lit(design.setpoints_n[i]),
            setpoint_text=f"{design.setpoints_n[i]:.6g}",
            kp=lit(design.kp[i]),
            ki=lit(design.ki[i]),
            kx=lit(design.kx[i]),
        )
        for i, axis in enumerate(AXES)
    )
    status = tuple(
        StatusSpec(
            name=check_identifier(b.name, "status bit").upper(),
            value=b.value,
            shift=b.value.bit_length() - 1,
            doc=tuple(textwrap.wrap(_comment_safe(b.doc), 84)),
        )
        for b in design.status_bits
    )
    if any(s.value <= 0 or s.value & (s.value - 1) for s in status):
        raise CodegenError(f"controller {name!r}: status bits must be distinct powers of two")
    missing = sorted(set(STATUS_USED) - {s.name for s in status})
    if missing:
        raise CodegenError(f"controller {name!r}: status bits {', '.join(missing)} not given")
    libm = {"sqrt"} | (set(surface.libm) if isinstance(surface, ExactSpec) else set())
    desc = tuple(textwrap.wrap(_comment_safe(" ".join(design.description.split())), 88)[:8])
    sha = design.source_sha256 or hashlib.sha256(repr(design).encode("utf-8")).hexdigest()
    adapt = None
    if design.adaptation is not None:
        adapt = _adaptation_code(design, lit)
    return ControllerCodeSpec(
        adapt=adapt,
        name=name,
        upper=name.upper(),
        module=module,
        surface_name=surface_name if fuzzy else "",
        target=tg.name,
        number_type=nt,
        ctype=tg.type_names[nt],
        fsuffix=tg.math_suffix[nt],
        version=__version__,
        source_file=_comment_safe(design.source_file),
        source_sha256=sha,
        description=desc,
        kind=design.kind,
        fuzzy=fuzzy,
        axes=axes,
        selected=tuple(i for i in range(3) if design.selection[i]),
        period=lit(design.period_s),
        correction=lit(design.correction_m),
        step=lit(design.step_m),
        limit=lit(design.limit_n),
        period_text=f"{design.period_s:.6g}",
        correction_text=f"{design.correction_m:.6g}",
        step_text=f"{design.step_m:.6g}",
        limit_text=f"{design.limit_n:.6g}",
        engage_at_start=design.engage_threshold_n is None,
        engage_threshold=lit(design.engage_threshold_n or 0.0),
        engage_samples=design.engage_samples,
        spike_gate=lit(design.spike_gate_n),
        spike_confirm=design.spike_confirm,
        trip_samples=design.trip_samples,
        backoff=lit(design.backoff_m),
        backoff_step=lit(backoff_step),
        tare_samples=design.tare_samples,
        has_tool=design.mass_kg is not None,
        weight=lit(weight),
        has_filter=design.lowpass_alpha != 1.0,
        alpha=lit(design.lowpass_alpha),
        zero=lit(0.0),
        one=lit(1.0),
        status=status,
        libm=tuple(sorted(libm)),
        surface=surface,
        surface_kind=(
            "surface_table"
            if isinstance(surface, TableSpec)
            else "surface_type2"
            if isinstance(surface, Type2Spec)
            else "surface"
        ),
        float_bound_note=tuple(textwrap.wrap(_float_note(design, nt), 88)),
        guid=_guid(design, nt, __version__),
        tunable=tg.tunable_parameters,
    )


def _adaptation_code(design: ControllerDesign, lit: Callable[[float], str]) -> AdaptationCode:
    ad = design.adaptation
    if ad is None or ad.mode not in ("stiffness-scheduled", "self-tuning"):
        raise CodegenError(f"controller {design.name!r}: unknown adaptation")
    scheduled = ad.mode == "stiffness-scheduled"
    numbers = [ad.forgetting, ad.min_step_m, ad.min_force_n, ad.initial_n_mm, ad.k_min_n_mm,
               ad.k_max_n_mm, ad.alpha_min, ad.alpha_max, *ad.ge, *ad.gde, ad.inner_q,
               ad.inner_a, ad.inner_g]  # fmt: skip
    numbers += [v for b in ad.bands for v in b if v is not None]
    numbers.append(ad.trust_span)
    numbers += [] if ad.inverse_n_mm is None else [ad.inverse_n_mm]
    numbers += [v for row in ad.alpha_table for v in row]
    if not all(math.isfinite(v) for v in numbers):
        raise CodegenError(f"controller {design.name!r}: adaptation parameters must be finite")
    bandless = ad.inverse_n_mm is not None
    if scheduled and (
        not (ad.bands or bandless) or ad.window < 1 or ad.delay < 1 or ad.dwell_periods < 1
    ):
        raise CodegenError(f"controller {design.name!r}: a schedule needs bands and a window")
    if not scheduled and (len(ad.alpha_table) != 7 or any(len(r) != 7 for r in ad.alpha_table)):
        raise CodegenError(f"controller {design.name!r}: alpha's rule table must be 7x7")
    return AdaptationCode(
        mode=ad.mode,
        scheduled=scheduled,
        history=ad.window + ad.delay,
        window=ad.window,
        delay=ad.delay,
        forgetting=lit(ad.forgetting),
        min_step=lit(ad.min_step_m),
        min_force=lit(ad.min_force_n),
        initial=lit(ad.initial_n_mm),
        k_min=lit(ad.k_min_n_mm),
        k_max=lit(ad.k_max_n_mm),
        band_limits=tuple(lit(up) for up, _ in ad.bands[:-1] if up is not None),
        band_scales=tuple(lit(scale) for _, scale in ad.bands),
        safe_band=max(ad.safe_band, 0),
        floor_band=max(ad.floor_band, 0),
        inverse=None if ad.inverse_n_mm is None else lit(ad.inverse_n_mm),
        trust=ad.trust_updates,
        trust_step=lit(ad.trust_span * ad.min_step_m),
        trust_force=lit(ad.trust_span * ad.min_force_n),
        dwell=ad.dwell_periods,
        alpha_low=lit(ad.alpha_min),
        alpha_span=lit(ad.alpha_max - ad.alpha_min),
        alpha_table=tuple(tuple(lit(v) for v in row) for row in ad.alpha_table),
        ge=(lit(ad.ge[0]), lit(ad.ge[1]), lit(ad.ge[2])),
        gde=(lit(ad.gde[0]), lit(ad.gde[1]), lit(ad.gde[2])),
        thousand=lit(1000.0),
        three=lit(3.0),
        jump=lit(ad.jump),
        spread=lit(ad.spread),
        contact=lit(ad.contact_n),
        inner_q=lit(ad.inner_q),
        inner_q1=lit(1.0 - ad.inner_q),
        inner_a=lit(ad.inner_a),
        inner_ag=lit((1.0 - ad.inner_a) * ad.inner_g),
    )


def emit_controller(
    design: ControllerDesign, target: str, number_type: str | None = None
) -> dict[str, str]:
    """Generate the controller's ``target`` sources: ``{relative path: text}``.

    C: ``NAME_controller.h``, ``NAME_controller.c`` and, for a fuzzy-PI, the surface's
    ``NAME_surface.h``, ``NAME_surface.c``; Python: ``NAME_controller.py``.
    """
    spec = build_controller_spec(design, target, number_type)
    files = render_files(target, spec.module, spec, "controller")
    if spec.fuzzy and "surface" in load_target(target).files:
        files |= render_files(target, spec.surface_name, spec.surface, spec.surface_kind)
    return files


__all__ = [
    "AdaptationDesign",
    "ControllerCodeSpec",
    "ControllerDesign",
    "StatusBit",
    "build_controller_spec",
    "emit_controller",
    "float_step_bound",
    "surface_table",
]
