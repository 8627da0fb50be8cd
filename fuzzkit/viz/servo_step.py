"""The MuJoCo arm's position servos answering a reference step, beside their design."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fuzzkit.plants.mujoco_arm import servo_step_response
from fuzzkit.plants.mujoco_model import ArmDynamics
from fuzzkit.viz.figures import new_figure

#: The step each joint is given (rad): small, so no servo reaches its torque limit.
STEP_RAD = 0.01


def servo_step_figure(dynamics: ArmDynamics | None = None, duration_s: float = 0.25) -> Any:
    """Each joint's link angle after a reference step of :data:`STEP_RAD` (normalised), the
    arm in free space at E1's start, against the designed critically damped response
    ``1 - (1 + w t) exp(-w t)`` at the servo bandwidth (docs/mujoco.md)."""
    dyn = dynamics or ArmDynamics()
    fig = new_figure(7.0, 4.0)
    ax = fig.add_subplot(1, 1, 1)
    w = 2.0 * math.pi * dyn.bandwidth_hz
    for joint in range(6):
        t, q = servo_step_response(joint, STEP_RAD, duration_s, dyn)
        ax.plot(t * 1e3, q / STEP_RAD, lw=1.2, label=f"axis {joint + 1}")
    t = np.linspace(0.0, duration_s, 500)
    ax.plot(t * 1e3, 1.0 - (1.0 + w * t) * np.exp(-w * t), "k--", lw=1.5, label="design")
    kind = "elastic axes 1-3" if dyn.elastic else "rigid joints"
    ax.set_title(
        f"IRB 140 in MuJoCo: position servo step\n{dyn.bandwidth_hz:g} Hz, "
        f"damping ratio {dyn.damping_ratio:g} ({kind})",
        fontsize=10,
    )
    ax.set_xlabel("time after the step (ms)")
    ax.set_ylabel(f"link angle / step ({STEP_RAD:g} rad)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", ncol=2)
    fig.tight_layout()
    return fig
