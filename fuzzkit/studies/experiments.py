"""The experiment model: a world plus the force-control task in it, and the shipped ones.

The experiments are data: scenario files (``fuzzkit/studies/scenarios/E1.yaml`` ...), loaded by
:mod:`fuzzkit.studies.scenario_file`. The shipped ones are the paper's three:

* E1: a cup carried along a nominal path meets an unexpected hammer lying on the table; on
  contact the force loop takes over (the path is held) and keeps 10 N along z, 0 N along x.
* E2: a straight path over a rough, slightly tilted and offset workpiece keeping 30 N along z.
* E3: the tool slides along the rough floor of a workpiece towards a side wall it does not know
  precisely, keeping 30 N along z and 6 N along x (pressing into the wall once it reaches it).

The runner drives any ``fuzzkit.plants.contract.ContactPlant``; forces and corrections are in the
task frame (``fuzzkit.plants.contract`` explains frames and signs). Metrics are computed on the
*true* contact force, so the sensor noise is not counted as control error.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from fuzzkit.control.names import AXES
from fuzzkit.errors import ConfigError
from fuzzkit.loop.task import DEFAULT_GAINS, DEFAULT_LATENCY, Experiment, with_spec

__all__ = [
    "AXES",
    "DEFAULT_GAINS",
    "DEFAULT_LATENCY",
    "EXPERIMENTS",
    "LOOP_GAIN_KEYS",
    "Experiment",
    "experiment",
    "press_experiment",
    "scaled_default_gains",
    "scaled_gains",
    "with_spec",
    "with_stiffness",
]
from fuzzkit.plants.environment import Box, Waypoint
from fuzzkit.studies.regulation import REGULATION_NAME, is_regulation, regulation_at

Vec = npt.NDArray[np.float64]

#: The shipped experiments: scenario files ``fuzzkit/studies/scenarios/<name>.yaml``.
EXPERIMENTS = ("E1", "E2", "E3")
#: Every shipped scenario: the experiments and the stability certificate's task (``regulate``).
SHIPPED_SCENARIOS = (*EXPERIMENTS, REGULATION_NAME)


def shipped_name(name: str) -> str | None:
    """The shipped scenario ``name`` stands for (case-insensitive), or None."""
    return next((s for s in SHIPPED_SCENARIOS if s.lower() == name.lower()), None)


@functools.lru_cache(maxsize=8)
def _shipped(text: str, source: str) -> Experiment:
    """A shipped scenario, parsed once per process for the same text: a tune, a sweep or a
    report asks for it for every run (the located reader costs about 50 ms a file). It names no
    other file, and the experiment is frozen, so sharing it is safe."""
    from fuzzkit.studies import scenario_file

    return scenario_file.loads_scenario(text, source)


def experiment(name: str) -> Experiment:
    """The experiment called ``name``: a shipped one (E1, E2, E3, regulate; case-insensitive)
    or the path of a scenario file (``.yaml``/``.yml``; see
    :mod:`fuzzkit.studies.scenario_file`)."""
    from fuzzkit.studies import scenario_file

    shipped = shipped_name(name)
    if shipped is not None:
        return _shipped(scenario_file.shipped_scenario_text(shipped), f"{shipped}.yaml")
    if name.lower().endswith((".yaml", ".yml")):
        return scenario_file.load_scenario(name)
    raise ConfigError(
        f"unknown experiment {name!r} (expected one of {', '.join(SHIPPED_SCENARIOS)} "
        "or a scenario .yaml file)"
    )


def with_stiffness(exp: Experiment, stiffness_n_per_m: float) -> Experiment:
    """The same experiment in an environment of another contact stiffness (the regulation
    task's approach speed follows it: :func:`fuzzkit.studies.regulation.regulation_at`)."""
    if is_regulation(exp):
        return regulation_at(exp, stiffness_n_per_m)
    scn = exp.scenario
    return replace(
        exp,
        scenario=replace(scn, contact=replace(scn.contact, stiffness_n_per_m=stiffness_n_per_m)),
    )


def press_experiment(stiffness_n_per_m: float, gap_m: float = 0.0002) -> Experiment:
    """E1's hammer, approached under force control from ``gap_m`` above it (path held).

    Isolates the force loop's stability from the impact of a moving approach: used for the
    stiffness study (10, 100, 1000 N/mm), where the approach speed is what the controller
    commands for a 10 N error.
    """
    e1 = experiment("E1")
    hammer = next(o for o in e1.scenario.objects if isinstance(o, Box))
    top = hammer.center_z + 0.5 * hammer.size_z
    x = hammer.center_x
    z = top + e1.scenario.tool.radius_m + gap_m
    scn = replace(
        e1.scenario,
        name="press",
        description="press on the hammer from just above it",
        path=(Waypoint(0.0, x, 0.0, z),),
        duration_s=3.0,
        contact=replace(e1.scenario.contact, stiffness_n_per_m=stiffness_n_per_m),
    )
    return replace(
        e1,
        name="press",
        title="press 10 N on the hammer",
        scenario=scn,
        engage_threshold_n=None,
        hold_path_on_contact=False,
    )


#: The gains that scale a controller's loop gain (the correction per newton of error): a PI's
#: ``kp`` and ``ki``, a fuzzy-PI's output factor ``kx``.
LOOP_GAIN_KEYS: dict[str, tuple[str, ...]] = {"pi": ("kp", "ki"), "fuzzy-pi": ("kx",)}


def scaled_default_gains(kind: str, factor: float) -> dict[str, float]:
    """The default gains of ``kind`` with the loop gain multiplied by ``factor``
    (:data:`LOOP_GAIN_KEYS`)."""
    g = dict(DEFAULT_GAINS[kind])
    for key in LOOP_GAIN_KEYS[kind]:
        g[key] *= factor
    return g


def scaled_gains(kind: str, stiffness_n_per_m: float) -> dict[str, float]:
    """Default gains scaled for another contact stiffness (same loop gain ``Ki*k`` per step).

    The loop gain of the incremental force loop is ``Ki * k`` per period; the defaults are tuned
    for ``k = 10 N/mm``, so the loop gain is scaled by ``1e4 / k``
    (:func:`scaled_default_gains`).
    """
    return scaled_default_gains(kind, 1.0e4 / stiffness_n_per_m)
