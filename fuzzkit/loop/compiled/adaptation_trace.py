"""The adaptation of a compiled run, per period: the generated controller's gain factor and
stiffness estimate, read through ``NAME_controller_adaptation``.

The compiled kernels record what every run records (forces, corrections, status bits) and
call only ``NAME_controller_step``. The controller is deterministic in the samples it
consumes, so its adaptation per period is read after the run: a fresh state of the same
compiled code steps the run's consumed samples (``RunResult.force``) with the run's tool
rotation, and ``NAME_controller_adaptation`` is read after each step. That is the replay
identity ``fuzzkit replay`` relies on, checked here on every period: each step's status bits
and correction must equal the run's, or the run is refused as a bug.
"""

from __future__ import annotations

import ctypes

import numpy as np

from fuzzkit.loop.compiled.generated_controller import GeneratedController
from fuzzkit.loop.result import RunResult


def record_adaptation(generated: GeneratedController, result: RunResult) -> None:
    """Fill ``result.gain_scale`` and ``result.stiffness_n_mm`` ((n, 3) each) from
    ``generated``, the adapting controller the compiled run ``result`` executed.

    Raises
    ------
    RuntimeError
        A step of the re-run differs from the run's (status bits or correction): the run did
        not execute this code on these samples.
    """
    read = generated.library.adaptation_function
    if read is None:
        raise RuntimeError(f"controller {generated.spec.name!r} has no adaptation to read")
    dptr = ctypes.POINTER(ctypes.c_double)
    state = generated.fresh_state()
    n = len(result.t)
    forces = np.ascontiguousarray(result.force, dtype=np.float64)
    rotations = np.ascontiguousarray(
        np.zeros((n, 9)) if result.rotation is None else result.rotation, dtype=np.float64
    )
    out = np.zeros(3)
    factor = np.empty((n, 3))
    stiffness = np.empty((n, 3))
    band = (ctypes.c_int * 3)()
    out_p = out.ctypes.data_as(dptr)
    for k in range(n):
        status = int(
            generated.step_function(
                state.ctypes.data,
                forces[k].ctypes.data_as(dptr),
                rotations[k].ctypes.data_as(dptr),
                out_p,
            )
        )
        if result.status is not None and status != int(result.status[k]):
            raise RuntimeError(
                f"period {k}: the controller's status {status:#x} differs from the run's "
                f"{int(result.status[k]):#x}"
            )
        if not np.array_equal(out, result.u[k]):
            raise RuntimeError(f"period {k}: the controller's correction differs from the run's")
        read(state.ctypes.data, factor[k].ctypes.data_as(dptr), stiffness[k].ctypes.data_as(dptr),
             band)  # fmt: skip
    result.gain_scale = factor
    result.stiffness_n_mm = stiffness
