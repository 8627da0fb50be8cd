"""The controller the node runs: the spec's generated C (where a compiler exists) or generated
Python, opened by :func:`fuzzkit.loop.controller_code.open_generated`, with its run-time
parameters by name, its tare and its reset.

Nothing here computes a correction: every step, tare, reset and parameter change is a call into
the generated code, so the node runs what ``fuzzkit compile`` ships and ``fuzzkit replay --impl
c`` (or ``python``) checks.
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping, Sequence
from typing import Any

from fuzzkit.control.names import AXES
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.loop.generated import GENERATED_IMPLS, open_generated_impl
from fuzzkit.ros2.parameters import refusal, tunable_values

#: ``--impl``: ``auto`` is the generated C where it compiles, else the generated Python
#: (the names of ``simulate --controller-impl`` and ``replay --impl``).
IMPLS = GENERATED_IMPLS


class ParameterRefused(ValueError):
    """A parameter change the controller refused; ``reason`` says why (nothing was changed)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class NodeController:
    """One generated controller (``impl``: ``c`` or ``python``) and its parameters.

    ``params`` are the run-time parameters by name (:func:`fuzzkit.ros2.parameters.tunable_values`
    gives the spec's); :meth:`set_params` changes some of them through the generated
    ``set_params``, after :func:`~fuzzkit.ros2.parameters.refusal` has had its say.
    """

    def __init__(self, spec: ControllerSpec, impl: str, generated: Any) -> None:
        self.spec = spec
        self.impl = impl
        self._ctl = generated
        self.params: dict[str, float] = tunable_values(spec)
        self._request_tare: Any = None
        if impl == "c":  # the C runner has no tare: call NAME_controller_request_tare itself
            self._request_tare = getattr(generated.library, f"{spec.name}_controller_request_tare")
            self._request_tare.argtypes = [ctypes.c_void_p]
            self._request_tare.restype = None

    def step(
        self, force_n: Sequence[float], tool_rotation: Sequence[float] | None
    ) -> tuple[list[float], int]:
        """One period: the correction ``u`` (m, x y z) and the status bits."""
        result: tuple[list[float], int] = self._ctl.step(force_n, tool_rotation)
        return result

    def reset(self) -> None:
        """The generated reset: no correction, not engaged or tripped; parameters kept."""
        self._ctl.reset()

    def tare(self) -> None:
        """The generated tare request: the next N valid samples are the new bias."""
        if self._request_tare is not None:
            self._request_tare(self._ctl.state)
        else:
            self._ctl.controller.tare()

    def set_params(self, changes: Mapping[str, float]) -> None:
        """Set the named parameters (all of them or none) from the next step on.

        Raises
        ------
        ParameterRefused
            A name that is not a run-time parameter, a value the spec's rules refuse, or one
            the generated ``set_params`` refuses; nothing changed.
        """
        why = refusal(self.spec, self.params, changes)
        if why is not None:
            raise ParameterRefused(why)
        new = {**self.params, **{k: float(v) for k, v in changes.items()}}
        try:
            self._ctl.set_params(params_vector(self.spec, new))
        except ValueError:
            raise ParameterRefused(
                "the generated controller's set_params refused the values"
            ) from None
        self.params = new


def params_vector(spec: ControllerSpec, params: Mapping[str, float]) -> list[float]:
    """The generated ``set_params`` order: set points, kp, ki, kx (x, y, z; a motion-only axis
    and a PI's kx 0), then correction_m, step_m."""
    chosen = {a.axis for a in spec.axes}

    def per_axis(what: str) -> list[float]:
        return [params.get(f"{what}_{a}", 0.0) if a in chosen else 0.0 for a in AXES]

    return [
        *per_axis("setpoint"),
        *per_axis("kp"),
        *per_axis("ki"),
        *per_axis("kx"),
        params["correction_m"],
        params["step_m"],
    ]


def open_node_controller(spec: ControllerSpec, impl: str = "auto") -> NodeController:
    """The spec's generated controller, opened as ``impl`` (:data:`IMPLS`), in double.

    Raises
    ------
    ToolchainError
        ``c`` asked for and no compiler, or the code does not compile.
    """
    if impl not in IMPLS:
        raise ValueError(f"unknown impl {impl!r} (expected one of {', '.join(IMPLS)})")
    target, generated = open_generated_impl(spec, impl, "double")
    return NodeController(spec, target, generated)
