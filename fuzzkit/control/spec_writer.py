"""ControllerSpec -> YAML text in the format :mod:`fuzzkit.control.spec_reader` reads.

Floats are written with ``repr`` precision, so reading the text back gives the same spec
(``fuzzkit tune --spec-out`` writes its result this way). Only the CLI writes files.
"""

from __future__ import annotations

from typing import Any

from fuzzkit.control.adaptation_spec import Adaptation
from fuzzkit.control.spec import DEFAULT_WATCHDOG_PERIODS, ControllerSpec, Surface


def spec_document(spec: ControllerSpec) -> dict[str, Any]:
    """The YAML document of ``spec`` as plain data (the reader's key order)."""
    doc: dict[str, Any] = {"name": spec.name}
    if spec.description:
        doc["description"] = spec.description
    doc["controller"] = spec.kind
    if spec.rulebase_ref is not None:
        doc["rulebase"] = spec.rulebase_ref
    doc["period_s"] = spec.period_s
    axes: dict[str, Any] = {}
    for a in spec.axes:
        gains = {"kp": a.kp, "ki": a.ki}
        if a.kx is not None:
            gains["kx"] = a.kx
        axes[a.axis] = {"setpoint_n": a.setpoint_n, "gains": gains}
    doc["axes"] = axes
    doc["limits"] = {"correction_m": spec.limits.correction_m, "step_m": spec.limits.step_m}
    s = spec.safety
    doc["safety"] = {
        "limit_n": s.limit_n,
        "engage": {"threshold_n": s.engage_threshold_n, "samples": s.engage_samples},
        "spike_gate": {"threshold_n": s.spike_gate_n, "confirm": s.spike_confirm},
        "trip": {"samples": s.trip_samples},
        "backoff": {"distance_m": s.backoff_m, "speed_m_s": s.backoff_speed_m_s},
    }
    if s.watchdog_periods != DEFAULT_WATCHDOG_PERIODS:  # written when it is not the default
        doc["safety"]["watchdog"] = {"periods": s.watchdog_periods}
    sensor = spec.sensor
    doc["sensor"] = {
        "tare": {"samples": sensor.tare_samples},
        "tool": None
        if sensor.tool is None
        else {"mass_kg": sensor.tool.mass_kg, "com_m": list(sensor.tool.com_m)},
        "lowpass_hz": sensor.lowpass_hz,
    }
    doc["adaptation"] = adaptation_document(spec.adaptation)
    if spec.kind == "fuzzy-pi":
        doc["surface"] = surface_document(spec.surface)
    if spec.inputs is not None:
        doc["inputs"] = list(spec.inputs)
    return doc


def surface_document(surface: Surface) -> Any:
    """The ``surface:`` section as plain data (``exact``, or the table's mapping)."""
    if surface.method == "exact":
        return "exact"
    doc: dict[str, Any] = {"method": surface.method}
    if surface.tolerance is not None:
        doc["tolerance"] = surface.tolerance
    if surface.resolution is not None:
        doc["resolution"] = surface.resolution
    return doc


def adaptation_document(ad: Adaptation) -> Any:
    """The ``adaptation:`` section as plain data (``none`` for fixed gains)."""
    if ad.mode == "none":
        return "none"
    if ad.mode == "self-tuning":
        doc: dict[str, Any] = {"mode": ad.mode, "alpha": {"min": ad.alpha_min, "max": ad.alpha_max}}
        if ad.error_n is not None:
            doc["error_n"] = ad.error_n
        if ad.change_n is not None:
            doc["change_n"] = ad.change_n
        return doc
    est = ad.estimator
    estimator: dict[str, object] = {
        "window_periods": est.window_periods,
        "delay_periods": est.delay_periods,
        "forgetting": est.forgetting,
        "min_step_m": est.min_step_m,
        "min_force_n": est.min_force_n,
        "initial_n_mm": est.initial_n_mm,
        "range_n_mm": [est.k_min_n_mm, est.k_max_n_mm],
    }
    if (est.inner_q, est.inner_a, est.inner_g) != (0.0, 0.0, 1.0):
        estimator["inner_loop"] = {"q": est.inner_q, "a": est.inner_a, "g": est.inner_g}
    if ad.inverse_n_mm is not None:
        return {"mode": ad.mode, "estimator": estimator, "inverse_n_mm": ad.inverse_n_mm}
    return {
        "mode": ad.mode,
        "estimator": estimator,
        "bands": [
            {"scale": b.scale}
            if b.up_to_n_mm is None
            else {"up_to_n_mm": b.up_to_n_mm, "scale": b.scale}
            for b in ad.bands
        ],
        "dwell_s": ad.dwell_s,
    }


def dump_spec(spec: ControllerSpec, header: str = "") -> str:
    """The YAML text of ``spec``, after ``header`` (comment lines, each starting with ``#``)."""
    import yaml

    body = yaml.safe_dump(spec_document(spec), sort_keys=False, default_flow_style=None)
    return header + body
