"""From a controller spec to its generated code and back: generate, compile or import, run.

``fuzzkit.codegen`` knows no controller spec (it reads the fuzzy model only), and
``fuzzkit.control`` no code generation; this module, above both, hands the spec to the
generator as plain data (:func:`design_of` -> ``codegen.controller.ControllerDesign``) and
opens what it generated as a runnable controller (:func:`open_generated`), for ``fuzzkit
compile SPEC``, ``fuzzkit replay --impl c`` and the tests.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fuzzkit.codegen.controller import (
    AdaptationDesign,
    ControllerDesign,
    StatusBit,
    emit_controller,
    surface_table,
)
from fuzzkit.codegen.target import load_target
from fuzzkit.control import status as st
from fuzzkit.control.adaptation import (
    ALPHA_TABLE,
    CONTACT,
    JUMP,
    SPREAD,
    TRUST_SPAN,
    TRUST_UPDATES,
)
from fuzzkit.control.controllers import Surface, lookup_table_surface
from fuzzkit.control.names import AXES
from fuzzkit.control.reference import input_gains
from fuzzkit.control.reference import spec_surface as exact_surface
from fuzzkit.control.spec import STANDARD_GRAVITY_M_S2, ControllerSpec, role_ordered
from fuzzkit.errors import ConfigError

#: What each status bit means, as the generated header and module document it.
STATUS_DOCS: Mapping[str, str] = {
    "ENGAGED": "The force loop has taken over (the engagement debounce passed); set until reset.",
    "HELD": "This sample did not reach the axis controllers (missing, rejected by the spike "
    "gate, or taken for the tare): the correction is held.",
    "TRIPPED": "The force safety limit tripped; latched until reset. The correction is frozen.",
    "RETREATING": "Tripped and still backing off (the back-off distance is not yet covered).",
    "SATURATED": "A correction limit acted in this step on some axis: |du| clamped to the step "
    "limit or |u| to the correction limit.",
    "TARING": "The tare is collecting free-air samples (the first N valid ones, or N after a "
    "request).",
    "REJECTED": "The spike gate rejected this sample (HELD is set too).",
    "UNTRUSTED": "The stiffness schedule does not trust its estimate yet (too few updates "
    "since the start or a sudden stiffening): the gain is its band of k_max.",
    "OUT_OF_RANGE": "The stiffness schedule read a contact stiffer than its range's k_max: "
    "the gain is its most conservative band's.",
}


def status_bits(scheduled: bool = False) -> tuple[StatusBit, ...]:
    """The reference's status bits (``fuzzkit.control.status``) with their meaning; those
    only a stiffness schedule sets (``SCHEDULE_BITS``) where ``scheduled``."""
    return tuple(
        StatusBit(name, bit, STATUS_DOCS[name])
        for name, bit in st.BITS.items()
        if scheduled or name not in st.SCHEDULE_BITS
    )


def design_of(spec: ControllerSpec) -> ControllerDesign:
    """The spec as the generator takes it: plain numbers, the rule base, the status bits."""
    by_axis = {a.axis: a for a in spec.axes}

    def per_axis(field: str) -> tuple[float, float, float]:
        vals = [getattr(by_axis[a], field) if a in by_axis else 0.0 for a in AXES]
        return (float(vals[0] or 0.0), float(vals[1] or 0.0), float(vals[2] or 0.0))

    safety = spec.safety
    tool = spec.sensor.tool
    source_file, sha = ("<spec>", "")
    if spec.source is not None:
        source_file, sha = Path(spec.source.path).name, spec.source.sha256
    return ControllerDesign(
        name=spec.name,
        kind=spec.kind,
        period_s=spec.period_s,
        selection=spec.selection,
        setpoints_n=spec.setpoints,
        kp=per_axis("kp"),
        ki=per_axis("ki"),
        kx=per_axis("kx"),
        correction_m=spec.limits.correction_m,
        step_m=spec.limits.step_m,
        limit_n=safety.limit_n,
        engage_threshold_n=safety.engage_threshold_n,
        engage_samples=safety.engage_samples,
        spike_gate_n=safety.spike_gate,
        spike_confirm=safety.spike_confirm,
        trip_samples=safety.trip_samples,
        backoff_m=safety.backoff_m,
        backoff_speed_m_s=safety.backoff_speed_m_s,
        tare_samples=spec.sensor.tare_samples,
        mass_kg=None if tool is None else tool.mass_kg,
        gravity_m_s2=STANDARD_GRAVITY_M_S2,
        lowpass_alpha=spec.sensor.lowpass_alpha(spec.period_s),
        rulebase=None if spec.rulebase is None else role_ordered(spec, spec.rulebase),
        status_bits=status_bits(spec.adaptation.mode == "stiffness-scheduled"),
        description=spec.description,
        source_file=source_file,
        source_sha256=sha,
        adaptation=adaptation_design(spec),
        surface_method=spec.surface.method,
        surface_tolerance=spec.surface.tolerance,
        surface_resolution=spec.surface.resolution,
    )


def spec_surface(spec: ControllerSpec) -> Surface:
    """What a fuzzy-PI spec's controller evaluates, as the generated double C does: the exact
    engine (``fuzzkit.control.reference.spec_surface``), or for ``surface: {method: table}`` the
    lookup table the generator builds (``codegen.controller.surface_table``), by its reference
    interpolation (bit for bit the generated double C's)."""
    if spec.surface.method != "table":
        return exact_surface(spec)
    rb = spec.rulebase
    if rb is None:
        raise ConfigError(f"controller spec {spec.name!r}: a {spec.kind} has no rule base")
    what = f"controller spec {spec.name!r}"
    table = surface_table(
        role_ordered(spec, rb), spec.surface.tolerance, spec.surface.resolution, what
    )
    return lookup_table_surface(table)


def adaptation_design(spec: ControllerSpec) -> AdaptationDesign | None:
    """The spec's adaptation as the generator takes it (None: fixed gains)."""
    ad = spec.adaptation
    if ad.mode == "none":
        return None
    est = ad.estimator
    ge = [0.0, 0.0, 0.0]
    gde = [0.0, 0.0, 0.0]
    for a in spec.axes:
        ge[a.index], gde[a.index] = input_gains(spec, a)
    return AdaptationDesign(
        mode=ad.mode,
        window=est.window_periods,
        delay=est.delay_periods,
        forgetting=est.forgetting,
        min_step_m=est.min_step_m,
        min_force_n=est.min_force_n,
        initial_n_mm=est.initial_n_mm,
        k_min_n_mm=est.k_min_n_mm,
        k_max_n_mm=est.k_max_n_mm,
        bands=tuple((b.up_to_n_mm, b.scale) for b in ad.bands),
        safe_band=ad.safe_band() if ad.bands else 0,
        floor_band=ad.floor_band() if ad.bands else 0,
        trust_updates=TRUST_UPDATES,
        trust_span=TRUST_SPAN,
        inverse_n_mm=ad.inverse_n_mm,
        dwell_periods=ad.dwell_periods(spec.period_s),
        alpha_min=ad.alpha_min,
        alpha_max=ad.alpha_max,
        alpha_table=ALPHA_TABLE,
        ge=(ge[0], ge[1], ge[2]),
        gde=(gde[0], gde[1], gde[2]),
        jump=JUMP,
        spread=SPREAD,
        contact_n=CONTACT * est.min_force_n,
        inner_q=est.inner_q,
        inner_a=est.inner_a,
        inner_g=est.inner_g,
    )


def generate(spec: ControllerSpec, target: str, number_type: str | None = None) -> dict[str, str]:
    """The generated controller's sources for ``target``: ``{relative path: text}``.

    Emitted once per process for an equal spec, target and number type: a tune, a sweep or a
    report asks for the same code for every run (the code of
    :func:`fuzzkit.loop.compiled.generated_controller.code_spec` leaves out the gains), and
    emitting it costs tens of ms. The spec is frozen; each caller gets its own dict."""
    return dict(_emitted(spec, target, number_type))


@functools.lru_cache(maxsize=64)
def _emitted(
    spec: ControllerSpec, target: str, number_type: str | None
) -> tuple[tuple[str, str], ...]:
    return tuple(emit_controller(design_of(spec), target, number_type).items())


def open_generated(spec: ControllerSpec, target: str, number_type: str | None = None) -> Any:
    """Generate the controller, then compile (C) or import (Python) it, ready to ``step``.

    Raises
    ------
    ToolchainError
        C: no compiler, or the code does not compile.
    """
    tg = load_target(target)
    nt = number_type or tg.default_number_type
    if tg.open_controller is None:  # pragma: no cover - every shipped target can run one
        raise NotImplementedError(f"the {target} target cannot run a generated controller")
    return tg.open_controller(generate(spec, target, nt), f"{spec.name}_controller", nt)
