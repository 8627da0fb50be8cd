"""Run a generated Python controller: import ``NAME_controller.py`` and drive its Controller."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.codegen.verify import load_module


class ImportedController:
    """The generated module, imported; ``step``, ``run`` and ``reset`` as the C runner's."""

    def __init__(self, files: Mapping[str, str], module: str) -> None:
        self.module: Any = load_module(files, module)
        self.controller: Any = self.module.Controller()

    def reset(self) -> None:
        """``Controller.reset``."""
        self.controller.reset()

    def set_params(self, params: Sequence[float]) -> None:
        """``Controller.set_params`` with ``params`` in the C runner's order (set points, kp,
        ki, kx per axis, correction_m, step_m).

        Raises
        ------
        ValueError
            The generated code refused them.
        """
        if len(params) != 14:
            raise ValueError(f"expected 14 parameters, got {len(params)}")
        p = [float(v) for v in params]
        ok = self.controller.set_params(
            setpoint_n=p[0:3], kp=p[3:6], ki=p[6:9], kx=p[9:12], correction_m=p[12], step_m=p[13]
        )
        if not ok:
            raise ValueError(f"the generated controller refused the parameters {p}")

    def step(
        self, force_n: Sequence[float], tool_rotation: Sequence[float] | None = None
    ) -> tuple[list[float], int]:
        """One period: ``(correction_m, status)``."""
        out, status = self.controller.step(force_n, tool_rotation)
        return list(out), int(status)

    def adaptation(self) -> tuple[list[float], list[float], list[int]]:
        """``Controller.adaptation``: the gain factor, the stiffness estimate (N/mm) and the
        band per task axis, as the C runner's.

        Raises
        ------
        ValueError
            The spec does not adapt its gains.
        """
        if not hasattr(self.controller, "adaptation"):
            raise ValueError("this generated controller does not adapt its gains")
        factor, k, band = self.controller.adaptation()
        return list(factor), list(k), list(band)

    def run(
        self, forces: npt.ArrayLike, rotations: npt.ArrayLike | None = None
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """``n`` periods: corrections ``(n, 3)`` and statuses, as the C runner's ``run``."""
        f = np.asarray(forces, dtype=np.float64).tolist()
        r = None if rotations is None else np.asarray(rotations, dtype=np.float64).tolist()
        out = np.empty((len(f), 3))
        status = np.zeros(len(f), dtype=np.int64)
        for k, force in enumerate(f):
            out[k], status[k] = self.controller.step(force, None if r is None else r[k])
        return out, status


def open_controller(files: Mapping[str, str], module: str, number_type: str) -> ImportedController:
    """The Python target's way to run a generated controller (``Target.open_controller``)."""
    return ImportedController(files, module)
