"""What a plant is to the loop: one adapter module per plant, registered here by name.

A plant's adapter (:class:`PlantAdapter`, defined as ``ADAPTER`` in ``fuzzkit/loop/<name>.py``)
says how the loop builds the plant and, where the plant has one, how its compiled period loop
runs. The registration (:data:`PLANTS`) names the adapter's module and what the plant is, so
that every ``--plant`` option lists the plants without importing them (choosing one plant never
imports another's dependencies: pymunk, MuJoCo). ``docs/architecture.md``, "Adding a plant",
says what a new plant takes.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

from fuzzkit.errors import ConfigError
from fuzzkit.plants.contract import ContactPlant

if TYPE_CHECKING:
    from fuzzkit.loop.compiled.common import ControllerArgs
    from fuzzkit.loop.result import RunResult
    from fuzzkit.loop.task import Experiment

#: A plant's compiled loop: ``(experiment, plant, controller arguments, seed) -> RunResult``,
#: every period in compiled code around the run's generated controller
#: (:class:`~fuzzkit.loop.compiled.common.ControllerArgs`). It raises
#: :class:`~fuzzkit.plants.contract.UnsupportedPlant` for a scenario its kernels lack.
CompiledRun = Callable[["Experiment", ContactPlant, "ControllerArgs", int], "RunResult"]


@dataclass(frozen=True)
class PlantAdapter:
    """How the loop runs one plant.

    ``make``: a fresh plant (a :class:`~fuzzkit.plants.contract.ContactPlant`; the Python loop,
    :func:`fuzzkit.loop.python_loop.run`, runs any). ``compiled``: the plant's compiled loop, or
    None (the Python loop runs it, with the same generated controller). ``reuse``: the compiled
    loop may keep one plant per process (its ``reset`` rebuilds the whole state), for a plant
    whose construction costs more than a short run.
    """

    name: str
    make: Callable[[], ContactPlant]
    compiled: CompiledRun | None = None
    reuse: bool = False


@dataclass(frozen=True)
class Registration:
    """A plant of the registry: its adapter as ``"module:ATTRIBUTE"`` and what the plant is,
    as ``--plant`` help lists it."""

    adapter: str
    summary: str


#: Plant name -> its registration: one line per plant.
PLANTS: dict[str, Registration] = {
    "planar": Registration("fuzzkit.loop.planar:ADAPTER", "pymunk planar two-link arm"),
    "arm6": Registration("fuzzkit.loop.arm6:ADAPTER", "6-DOF IRB 140, kinematic"),
    "mujoco": Registration("fuzzkit.loop.mujoco:ADAPTER", "the IRB 140 in MuJoCo, dynamic"),
    "mujoco-elastic": Registration(
        "fuzzkit.loop.mujoco:ELASTIC", "the MuJoCo IRB 140 with joint springs"
    ),
}


def plants_text() -> str:
    """Every plant of the registry with what it is: ``arm6 (6-DOF IRB 140, kinematic), ...``."""
    return ", ".join(f"{name} ({entry.summary})" for name, entry in sorted(PLANTS.items()))


@cache
def adapter(name: str) -> PlantAdapter:
    """The adapter of the plant registered as ``name``.

    Raises
    ------
    ConfigError
        No plant of that name.
    """
    entry = PLANTS.get(name)
    if entry is None:
        raise ConfigError(f"unknown plant {name!r} (expected one of {', '.join(sorted(PLANTS))})")
    module_name, _, attr = entry.adapter.partition(":")
    found: PlantAdapter = getattr(importlib.import_module(module_name), attr)
    return found


def make_plant(name: str) -> ContactPlant:
    """A fresh plant registered as ``name`` (see :data:`PLANTS`)."""
    return adapter(name).make()


@cache
def _reused(name: str) -> ContactPlant:
    return adapter(name).make()


def compiled_plant(name: str) -> ContactPlant:
    """The plant ``name`` for a compiled run: one per process where its adapter allows
    (``reuse``), else a fresh one."""
    return _reused(name) if adapter(name).reuse else make_plant(name)


def compiled_supports(plant: str) -> bool:
    """True when the plant registered as ``plant`` has a compiled loop."""
    return plant in PLANTS and adapter(plant).compiled is not None


def compiled_plants() -> tuple[str, ...]:
    """The registered plants that have a compiled loop, in name order."""
    return tuple(name for name in sorted(PLANTS) if compiled_supports(name))
