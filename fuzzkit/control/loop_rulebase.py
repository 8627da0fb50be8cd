"""What a rule base must be to run as the fuzzy-PI's surface in the closed loop, checked first.

The fuzzy-PI (:class:`fuzzkit.control.controllers.FuzzyPI`) feeds its surface ``Ki*e`` and
``Kp*de`` clipped to the normalised universe [-1, 1] and multiplies the answer by ``Kx`` (metres
per period). So the rule base must have exactly two inputs, each on [-1, 1], whatever their names
(roles by position, the error first, or by a controller spec's ``inputs:``), and one output, a
normalised correction: its range contains 0 and lies within
[-OUTPUT_SCALE_LIMIT, OUTPUT_SCALE_LIMIT].

A rule base on another scale (say [-100, 100]) is refused, not mapped: the gains already are
the scaling, and a silent second scaling would multiply the correction (a rule base on
[-100, 100] drives the arm to 195 N against a 25 N limit). The fix is to rescale the universes
(divide every term's points by the range's half width) and let Ki, Kp, Kx carry the units.
"""

from __future__ import annotations

import os
from functools import lru_cache
from typing import TYPE_CHECKING

from fuzzkit.errors import ConfigError
from fuzzkit.fuzzy.model import RuleBase, Variable

if TYPE_CHECKING:
    from fuzzkit.control.controllers import Surface

#: The universe the controller hands the rule base: Ki*e and Kp*de are clipped to it.
INPUT_RANGE = (-1.0, 1.0)
#: The largest normalised correction a rule base's output range may reach. A Mamdani output
#: stays within its range; a Sugeno output is a weighted average of its terms (the shipped
#: sugeno_pi reaches 1.6 at the corners and declares [-2, 2]). A larger range is another scale.
OUTPUT_SCALE_LIMIT = 2.0
_EPS = 1e-9


def loop_problems(rb: RuleBase) -> list[str]:
    """What keeps ``rb`` from running as the fuzzy-PI's surface (empty when it can)."""
    problems: list[str] = []
    if len(rb.inputs) != 2:
        problems.append(
            f"exactly two inputs are needed (the scaled error and its change), got "
            f"{_listing(rb.inputs)}"
        )
    for role, var in zip(("Ki*e", "Kp*de"), rb.inputs, strict=False):
        if _input_off_scale(var):
            problems.append(
                f"input {var.name} must be on [-1, 1] (the controller clips {role} to it), "
                f"got {_range(var)}"
            )
    if len(rb.outputs) != 1:
        problems.append(f"exactly one output is needed, got {_listing(rb.outputs)}")
    else:
        out = rb.outputs[0]
        if _output_off_scale(out):
            problems.append(
                f"output {out.name} is a normalised correction (scaled by Kx): its range must "
                f"contain 0 and lie within [-{OUTPUT_SCALE_LIMIT:g}, {OUTPUT_SCALE_LIMIT:g}], "
                f"got {_range(out)}"
            )
    return problems


def check_loop_rulebase(rb: RuleBase, spec: str | os.PathLike[str] | None = None) -> None:
    """Raise a :class:`~fuzzkit.errors.ConfigError` naming every problem and the fix when ``rb``
    cannot run as the fuzzy-PI's surface; ``spec`` is how the user named it.

    Raises
    ------
    ConfigError
        Not two inputs on [-1, 1], or not one output within the scale limit.
    """
    problems = loop_problems(rb)
    if not problems:
        return
    where = spec if spec is not None else (rb.source.path if rb.source else rb.name)
    lines = "\n".join(f"  - {p}" for p in problems)
    raise ConfigError(
        f"rule base {where} cannot run as the fuzzy-PI in the closed loop:\n{lines}\n"
        "  the loop needs two inputs (the error, then its change, unless a spec's inputs: "
        "maps them), each on [-1, 1], and one output within "
        f"[-{OUTPUT_SCALE_LIMIT:g}, {OUTPUT_SCALE_LIMIT:g}] (the controller feeds it Ki*e and "
        "Kp*de clipped to [-1, 1] and multiplies its output by Kx)"
        + (_RESCALE if _off_scale(rb) else "")
    )


_RESCALE = (
    "\n  fix: rescale each universe to [-1, 1] (divide every term's points by the range's half "
    "width); the gains Ki, Kp, Kx then carry the physical scale (see docs/simulation.md, 'Your "
    "own rule base in the loop')"
)


def _input_off_scale(var: Variable) -> bool:
    return abs(var.low - INPUT_RANGE[0]) > _EPS or abs(var.high - INPUT_RANGE[1]) > _EPS


def _output_off_scale(out: Variable) -> bool:
    return not (out.low <= 0.0 <= out.high) or max(-out.low, out.high) > OUTPUT_SCALE_LIMIT + _EPS


def _off_scale(rb: RuleBase) -> bool:
    """Whether some universe of ``rb`` is on another scale than the loop's (the advice to
    rescale applies only then)."""
    return any(_input_off_scale(v) for v in rb.inputs[:2]) or any(
        _output_off_scale(v) for v in rb.outputs[:1]
    )


@lru_cache(maxsize=8)
def load_loop_rulebase(spec: str) -> RuleBase:
    """Load a rule base (shipped name or file) and check it can run as the fuzzy-PI's surface.

    Raises
    ------
    RuleBaseError
        The file is malformed or the name unknown.
    ConfigError
        It is well formed but not a fuzzy-PI surface (:func:`check_loop_rulebase`).
    """
    from fuzzkit.formats.registry import load

    rb = load(spec)
    check_loop_rulebase(rb, spec)
    return rb


#: The roles of a rule base's inputs when no controller spec maps them: by position, the
#: error first, its change second (``fuzzkit.control.spec.surface_inputs`` under a spec).
POSITIONAL_ROLES = (0, 1)


def role_names(rb: RuleBase, roles: tuple[int, int] = POSITIONAL_ROLES) -> tuple[str, str, str]:
    """The rule base's own names of the error input, the change-of-error input and the
    output, with the inputs at positions ``roles`` (``fuzzkit.control.spec.surface_inputs``
    under a spec): the only place the loop learns them, so that no code assumes ``e``, ``de``
    or ``du``."""
    return rb.inputs[roles[0]].name, rb.inputs[roles[1]].name, rb.outputs[0].name


@lru_cache(maxsize=16)
def exact_surface(rb: RuleBase, roles: tuple[int, int] = POSITIONAL_ROLES) -> Surface:
    """The exact engine's surface of ``rb`` as the fuzzy-PI calls it, ``(Ki*e, Kp*de) ->
    output``, its inputs in the roles ``roles`` (:func:`role_names`); built once per rule base
    and roles."""
    from fuzzkit.control.controllers import engine_surface
    from fuzzkit.fuzzy.inference import Engine

    return engine_surface(Engine(rb), *role_names(rb, roles))


def _range(var: Variable) -> str:
    return f"[{var.low:g}, {var.high:g}]"


def _listing(variables: tuple[Variable, ...]) -> str:
    if not variables:
        return "none"
    return ", ".join(f"{v.name} {_range(v)}" for v in variables)
