"""JSON Schema (draft 2020-12) of the controller-spec YAML format (``fuzzkit schema
--controller``), for editors and linters.

Structural only: keys, types, required entries and simple bounds. The reader
(:mod:`fuzzkit.control.spec_reader`) also checks what a schema cannot say (a set point below
the safety limit, a rule base that loads, a corner below the Nyquist frequency).
"""

from __future__ import annotations

from typing import Any

from fuzzkit.control.adaptation_spec import MAX_HISTORY
from fuzzkit.control.names import AXES, GAIN_KEYS, KINDS
from fuzzkit.control.spec import (
    ADAPTATIONS,
    MAX_PERIOD_S,
    MAX_RESOLUTION,
    MIN_PERIOD_S,
    MIN_RESOLUTION,
    SURFACE_METHODS,
)
from fuzzkit.control.spec_reader import MAX_SAMPLES, REQUIRED_KEYS


def _number(
    description: str, minimum: float | None = None, exclusive: bool = False
) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "number", "description": description}
    if minimum is not None:
        out["exclusiveMinimum" if exclusive else "minimum"] = minimum
    return out


def _count(description: str, minimum: int) -> dict[str, Any]:
    return {
        "type": "integer",
        "minimum": minimum,
        "maximum": MAX_SAMPLES,
        "description": description,
    }


def _object(props: dict[str, Any], required: tuple[str, ...] = (), **extra: Any) -> dict[str, Any]:
    return {
        "type": "object",
        "properties": props,
        "required": list(required),
        "additionalProperties": False,
        **extra,
    }


def adaptation_schema() -> dict[str, Any]:
    """The ``adaptation:`` section: a mode name, or a mapping whose keys depend on the mode."""
    window = "increments over this many periods"
    estimator = _object(
        {
            "window_periods": {**_count(window, 1), "maximum": MAX_HISTORY - 1},
            "delay_periods": {
                **_count("1 + the loop's latency (periods)", 1),
                "maximum": MAX_HISTORY - 1,
            },
            "forgetting": {**_number("weight of the past per update", 0, True), "maximum": 1},
            "min_step_m": _number("excitation threshold on |du| over the window (m)", 0, True),
            "min_force_n": _number("excitation threshold on |df| over the window (N)", 0, True),
            "initial_n_mm": _number("the estimate before the first update (N/mm)", 0, True),
            "range_n_mm": {
                "type": "array",
                "items": {"type": "number", "exclusiveMinimum": 0},
                "minItems": 2,
                "maxItems": 2,
                "description": "[k_min, k_max] (N/mm): the estimate is clamped to it",
            },
            "inner_loop": _object(
                {
                    "q": {**_number("the first lag's pole", 0, False), "exclusiveMaximum": 1},
                    "a": {**_number("the second lag's pole", 0, False), "exclusiveMaximum": 1},
                    "g": _number("the inner loop's DC gain", 0, True),
                }
            ),
        }
    )
    band = _object(
        {
            "up_to_n_mm": _number("the band holds estimates up to this (N/mm)", 0, True),
            "scale": _number("factor of the output gain in this band", 0, True),
        },
        ("scale",),
    )
    scheduled = _object(
        {
            "mode": {"const": "stiffness-scheduled"},
            "estimator": estimator,
            "bands": {"type": "array", "items": band, "minItems": 1},
            "inverse_n_mm": _number(
                "the 1/k schedule (instead of bands): factor min(1, inverse_n_mm / k)", 0, True
            ),
            "dwell_s": _number("least time between two band changes that raise the gain", 0),
        },
        ("mode",),
    )
    tuning = _object(
        {
            "mode": {"const": "self-tuning"},
            "alpha": _object(
                {
                    "min": {**_number("the factor at alpha = 0", 0), "maximum": 1},
                    "max": {**_number("the factor at alpha = 1", 0, True), "maximum": 1},
                }
            ),
            "error_n": _number("E = clip(e / error_n) (N); a pi needs it", 0, True),
            "change_n": _number("dE = clip(de / change_n) (N); a pi needs it", 0, True),
        },
        ("mode",),
    )
    return {
        "oneOf": [
            {"enum": list(ADAPTATIONS)},
            _object({"mode": {"const": "none"}}, ("mode",)),
            scheduled,
            tuning,
        ],
        "description": "online adaptation of the output scaling factor (docs/controller.md)",
    }


def surface_schema() -> dict[str, Any]:
    """The ``surface:`` section: ``exact``, or a table sized by tolerance or resolution."""
    table = _object(
        {
            "method": {"const": "table"},
            "tolerance": {
                **_number("certified largest error, fraction of the output's range", 0, True),
                "exclusiveMaximum": 1,
            },
            "resolution": {
                "type": "integer",
                "minimum": MIN_RESOLUTION,
                "maximum": MAX_RESOLUTION,
                "description": "breakpoints per input (instead of tolerance)",
            },
        },
        ("method",),
        oneOf=[{"required": ["tolerance"]}, {"required": ["resolution"]}],
    )
    return {
        "oneOf": [
            {"enum": [SURFACE_METHODS[0]]},
            _object({"method": {"const": "exact"}}, ("method",)),
            table,
        ],
        "description": "fuzzy-pi only: how the rule base's surface is evaluated, by every "
        "command (docs/controller.md)",
    }


def json_schema() -> dict[str, Any]:
    """The schema of a controller spec (see ``docs/controller.md`` for every field)."""
    gains = {
        "kp": _number("pi: gain on the change of error (m/N); fuzzy-pi: scale of de (1/N)", 0),
        "ki": _number("pi: gain on the error (m/N); fuzzy-pi: scale of e (1/N)", 0),
        "kx": _number("fuzzy-pi only: scale of the surface's output (m per period)", 0, True),
    }
    axis = _object(
        {
            "setpoint_n": _number("force set point f_d (N): what the tool exerts on the surface"),
            "gains": _object(gains, GAIN_KEYS["pi"]),
        },
        ("setpoint_n", "gains"),
    )
    nullable_threshold = {
        "type": ["number", "null"],
        "minimum": 0,
    }
    safety = _object(
        {
            "limit_n": _number("force safety limit on every axis (N)", 0, True),
            "engage": _object(
                {
                    "threshold_n": {
                        **nullable_threshold,
                        "description": "engage once a force exceeds it (N); null: at once",
                    },
                    "samples": _count("consecutive valid samples above the threshold", 1),
                }
            ),
            "spike_gate": _object(
                {
                    "threshold_n": {
                        "type": ["number", "null"],
                        "exclusiveMinimum": 0,
                        "description": "largest accepted jump from the last accepted sample "
                        "(N); null: half of limit_n",
                    },
                    "confirm": _count("rejections in a row that confirm a real step", 1),
                }
            ),
            "trip": _object({"samples": _count("consecutive samples above limit_n to trip", 1)}),
            "watchdog": _object(
                {"periods": _count("periods without a sample that stop a deployed loop", 1)}
            ),
            "backoff": _object(
                {
                    "distance_m": _number("retreat distance after a trip (m)", 0, True),
                    "speed_m_s": _number("retreat speed (m/s)", 0, True),
                }
            ),
        },
        ("limit_n",),
    )
    sensor = _object(
        {
            "tare": _object(
                {"samples": _count("free-air samples averaged into the bias; 0: no tare", 0)},
                ("samples",),
            ),
            "tool": {
                "oneOf": [
                    {"type": "null"},
                    _object(
                        {
                            "mass_kg": _number("tool mass below the sensor (kg)", 0),
                            "com_m": {
                                "type": "array",
                                "items": {"type": "number"},
                                "minItems": 3,
                                "maxItems": 3,
                                "description": "centre of mass, sensor frame (m)",
                            },
                        },
                        ("mass_kg",),
                    ),
                ],
                "description": "gravity compensation; null or absent: off",
            },
            "lowpass_hz": {
                "type": ["number", "null"],
                "exclusiveMinimum": 0,
                "description": "first-order low-pass corner (Hz), below 1 / (2 period_s); "
                "null: no filter",
            },
        }
    )
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "fuzzkit controller spec",
        **_object(
            {
                "name": {
                    "type": "string",
                    "pattern": r"^[A-Za-z_][A-Za-z0-9_]*$",
                    "description": "C identifier prefixing the generated symbols",
                },
                "description": {"type": "string"},
                "controller": {"enum": list(KINDS)},
                "rulebase": {
                    "type": "string",
                    "description": "fuzzy-pi only: shipped name or path (relative to the spec)",
                },
                "period_s": {
                    "type": "number",
                    "minimum": MIN_PERIOD_S,
                    "maximum": MAX_PERIOD_S,
                    "description": "outer-loop sample period T (s)",
                },
                "axes": _object(
                    {a: axis for a in AXES},
                    minProperties=1,
                    description="the selection matrix: force-controlled task axes",
                ),
                "limits": _object(
                    {
                        "correction_m": _number("largest |u| per axis (m)", 0, True),
                        "step_m": _number("largest |du| per period (m)", 0, True),
                    },
                    ("correction_m", "step_m"),
                ),
                "safety": safety,
                "sensor": sensor,
                "adaptation": adaptation_schema(),
                "surface": surface_schema(),
                "inputs": {
                    "type": "array",
                    "items": {"type": "string"},
                    "minItems": 2,
                    "maxItems": 2,
                    "description": "fuzzy-pi only: the rule base's input names in role order "
                    "[error, change of error]; absent: by position",
                },
            },
            REQUIRED_KEYS,
            allOf=[
                {
                    "if": {"properties": {"controller": {"const": "fuzzy-pi"}}},
                    "then": {"required": ["rulebase"]},
                    "else": {"not": {"required": ["rulebase"]}},
                }
            ],
        ),
    }
