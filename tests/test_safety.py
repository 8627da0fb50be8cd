"""The safety matrix: every experiment x controller x fault kind x plant over noise seeds, on
the reference controller and on the generated C controller.

``reference``: fuzzkit's controller in the Python loop (the exact engine as the fuzzy-PI's
surface). ``generated-c``: the controller spec of the same settings
(:func:`~fuzzkit.loop.compiled.generated_controller.run_controller_spec`) generated as C
(double), compiled, and run whole inside the compiled loop: what ``--controller-impl c``
runs and what ships. For every run: the *true* contact force stays below the experiment's
safety limit, the loop does not trip, every force-controlled axis with a set point reaches
contact, and the set point is held at the end (after the fault). Faults at the strength of
``fuzzkit.loop.faults.FAULTS``.

Each matrix runs twice over (tests/_pairwise.py): ``make test`` its covering set (every pair
of values of any two axes in some row) at seeds 0 and 1, ``make verify`` (``-m verify``) the
full product at 50 seeds (the MuJoCo reference rows at :data:`MUJOCO_VERIFY_SEEDS`).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _pairwise import matrix_params

from fuzzkit.control.controllers import Surface
from fuzzkit.loop.compiled.generated_controller import (
    GeneratedController,
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.loop.compiled_loop import run_compiled
from fuzzkit.loop.faults import FAULTS, fault
from fuzzkit.loop.python_loop import load_surface, run
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import EXPERIMENTS, experiment

IMPLS = ("reference", "generated-c")
CONTROLLERS = ("pi", "fuzzy-pi")
PLANTS = ("planar", "arm6")
#: The generated C controller needs a C compiler.
IMPL_MARKS = {"generated-c": needs_cc}
#: The reference controller on the MuJoCo plant runs in the Python loop (about 15x slower than
#: the compiled loop): ``make verify`` runs that product at fewer seeds, and the generated C
#: controller's, in the compiled loop, at the other plants' 50 (docs/development.md gives the
#: measured cost).
MUJOCO_VERIFY_SEEDS = tuple(range(10))

#: Shortest runs that still cover contact, the faults (the dropout is at 2.2-2.3 s) and a
#: steady stretch after them; None: the experiment's own duration (E3 meets its wall at 4.2 s).
DURATION_S = {"E1": 3.5, "E2": 5.0, "E3": None}
#: (plant, experiment, controller, axis) where the force need not settle: PI on the elastic
#: arm can ring against E3's wall (docs/mujoco.md, "Joint elasticity is where the loop starts
#: to ring"; a limit cycle some seeds and faults excite and others not). There the force is
#: either held or still swinging (std over the final 0.5 s above :data:`RINGING_STD_N`), never
#: settled off its set point; everything else is checked as elsewhere.
RINGING = {("mujoco-elastic", "E3", "pi", 0)}
RINGING_STD_N = 2.0
#: Largest error of the mean true force over the final 0.5 s. E2 still slides over the rough
#: workpiece then, so its force wanders more.
HOLD_TOLERANCE_N = {"E1": 0.5, "E2": 1.5, "E3": 0.5}


@functools.cache
def _surface() -> Surface:
    return load_surface("macvicar_whelan")


@functools.cache
def _generated(name: str, controller: str) -> GeneratedController:
    return load_generated_controller(run_controller_spec(experiment(name), controller, None))


def _run(
    impl: str, name: str, controller: str, fault_kind: str, plant: str, seed: int
) -> RunResult:
    exp = experiment(name)
    if impl == "generated-c":
        r = run_compiled(
            exp,
            plant,
            seed=seed,
            faults=fault(fault_kind, seed),
            duration_s=DURATION_S[name],
            generated_controller=_generated(name, controller),
        )
        assert r.controller_impl.startswith("generated C controller (double)")
        return r
    return run(
        exp,
        plant,
        controller,
        surface=_surface() if controller == "fuzzy-pi" else None,
        seed=seed,
        faults=fault(fault_kind, seed),
        duration_s=DURATION_S[name],
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    "impl, name, controller, fault_kind, plant, seed",
    matrix_params(
        [IMPLS, sorted(EXPERIMENTS), CONTROLLERS, sorted(FAULTS), PLANTS], marks=IMPL_MARKS
    ),
)
def test_faults_never_push_the_true_force_past_the_limit_and_the_task_gets_done(
    impl: str, name: str, controller: str, fault_kind: str, plant: str, seed: int
) -> None:
    exp = experiment(name)
    r = _run(impl, name, controller, fault_kind, plant, seed)
    peak = float(np.max(np.abs(r.force_true)))
    assert peak < exp.force_limit_n, f"true force {peak:.1f} N"
    assert not r.tripped
    tail = r.t >= r.t[-1] - 0.5
    for axis in (i for i in range(3) if exp.selection[i]):
        setpoint = exp.setpoints[axis]
        if setpoint != 0.0:  # contact reached along every axis that must push
            assert float(np.max(r.force_true[:, axis])) >= 0.9 * setpoint, axis
        held = float(np.mean(r.force_true[tail, axis]))
        if (plant, name, controller, axis) in RINGING:
            swing = float(np.std(r.force_true[tail, axis]))
            if swing > RINGING_STD_N:  # the documented ringing
                continue
        assert abs(held - setpoint) < HOLD_TOLERANCE_N[name], (axis, held)
    if fault_kind in ("nan", "dropout", "spike"):
        assert r.faults > 0  # the bad samples were seen, counted and held


@pytest.mark.slow
@pytest.mark.parametrize(
    "name, controller, fault_kind, seed",
    matrix_params(
        [sorted(EXPERIMENTS), CONTROLLERS, sorted(FAULTS)], verify_seeds=MUJOCO_VERIFY_SEEDS
    ),
)
def test_the_dynamic_mujoco_arm_passes_the_same_matrix(
    name: str, controller: str, fault_kind: str, seed: int
) -> None:
    """The same matrix on the IRB 140 in MuJoCo, the reference controller in the Python loop."""
    test_faults_never_push_the_true_force_past_the_limit_and_the_task_gets_done(
        "reference", name, controller, fault_kind, "mujoco", seed
    )


#: The IRB 140 in MuJoCo, rigid and with joint springs on axes 1-3.
MUJOCO_PLANTS = ("mujoco", "mujoco-elastic")


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize(
    "name, controller, fault_kind, plant, seed",
    matrix_params([sorted(EXPERIMENTS), CONTROLLERS, sorted(FAULTS), MUJOCO_PLANTS]),
)
def test_the_dynamic_mujoco_arm_passes_the_matrix_on_the_generated_controller(
    name: str, controller: str, fault_kind: str, plant: str, seed: int
) -> None:
    """The same matrix on the IRB 140 in MuJoCo, rigid and elastic, the generated C controller
    in the compiled loop (what ships, at every seed of the other plants)."""
    test_faults_never_push_the_true_force_past_the_limit_and_the_task_gets_done(
        "generated-c", name, controller, fault_kind, plant, seed
    )


SPEC_EXAMPLES = ("controller.yaml", "controller_pi.yaml")


@pytest.mark.slow
@pytest.mark.parametrize(
    "impl, spec_file, fault_kind, plant, seed",
    matrix_params(
        [IMPLS, SPEC_EXAMPLES, sorted(FAULTS), PLANTS], verify_seeds=(0,), marks=IMPL_MARKS
    ),
)
def test_the_shipped_specs_pass_the_safety_matrix(
    impl: str, spec_file: str, fault_kind: str, plant: str, seed: int
) -> None:
    """The example controller specs (E1's task), sensor front end and all, on E1 with every
    fault kind, as the reference and as generated C in the compiled loop: below the limit, no
    trip, the set point held."""
    name = "E1"
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.studies.experiments import with_spec

    spec = load_spec(Path(__file__).resolve().parent.parent / "docs" / "examples" / spec_file)
    exp = with_spec(experiment(name), spec)
    if impl == "generated-c":
        r = run_compiled(
            exp,
            plant,
            seed=seed,
            faults=fault(fault_kind, seed),
            duration_s=DURATION_S[name],
            generated_controller=load_generated_controller(spec),
        )
        assert r.controller_impl.startswith("generated C controller (double)")
    else:
        r = run(exp, plant, seed=seed, faults=fault(fault_kind, seed), duration_s=DURATION_S[name])
    assert float(np.max(np.abs(r.force_true))) < exp.force_limit_n
    assert not r.tripped
    tail = r.t >= r.t[-1] - 0.5
    for axis in (i for i in range(3) if exp.selection[i]):
        held = float(np.mean(r.force_true[tail, axis]))
        assert abs(held - exp.setpoints[axis]) < HOLD_TOLERANCE_N[name], (axis, held)
