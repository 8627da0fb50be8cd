"""The node's ROS parameters: the spec's run-time parameters by name, and why a value is refused.

The names are the FMU's tunable parameters and ``replay --schedule``'s
(:func:`fuzzkit.studies.param_schedule.parameter_names`): per force-controlled axis ``kp_A``,
``ki_A`` (and ``kx_A`` for a fuzzy-PI) and ``setpoint_A`` (N); and the correction limits
``correction_m`` and ``step_m`` (m), which the generated controller takes at run time too.
``limit_n``, the force safety limit, is built into the generated code: the node declares it
read-only.
"""

from __future__ import annotations

from collections.abc import Mapping

from fuzzkit.control.spec import ControllerSpec
from fuzzkit.studies.param_schedule import parameter_names, value_problem

#: The correction limits, run-time parameters of every spec.
LIMITS = ("correction_m", "step_m")
#: The one read-only parameter: the safety limit, baked into the generated code.
READ_ONLY = "limit_n"


def tunable_values(spec: ControllerSpec) -> dict[str, float]:
    """Every run-time parameter of ``spec`` with the spec's value, in declaration order."""
    by_axis = {a.axis: a for a in spec.axes}
    values: dict[str, float] = {}
    for name in parameter_names(spec):
        if name == READ_ONLY:
            continue
        what, axis = name.rsplit("_", 1)
        a = by_axis[axis]
        value = a.setpoint_n if what == "setpoint" else getattr(a, what)
        values[name] = float(value)
    values["correction_m"] = float(spec.limits.correction_m)
    values["step_m"] = float(spec.limits.step_m)
    return values


def refusal(
    spec: ControllerSpec, current: Mapping[str, float], changes: Mapping[str, float]
) -> str | None:
    """Why ``changes`` (name -> value) cannot be applied to the parameters ``current``, or None.

    The checks are ``replay --schedule``'s (:func:`~fuzzkit.studies.param_schedule.value_problem`)
    and the generated ``set_params``': finite values, a fuzzy-PI's scaling factors > 0, a PI's
    gains >= 0, correction limits > 0, every set point's size below the safety limit.
    """
    limit = spec.safety.limit_n
    for name, value in changes.items():
        if name == READ_ONLY:
            return f"{READ_ONLY} is built into the generated controller: regenerate to change it"
        if name not in current:
            return f"{name} is not a run-time parameter (these are: {', '.join(current)})"
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            return f"{name} must be a number, got {value!r}"
        v = float(value)
        why = value_problem(spec, name, v)
        if why is not None:
            return why
        if name in LIMITS and not v > 0.0:
            return f"{name} must be > 0 (m), got {v:g}"
        if name.startswith("setpoint_") and not abs(v) < limit:
            return (
                f"{name} = {v:g} N: a set point's size must stay below the safety limit "
                f"limit_n = {limit:g} N"
            )
    return None
