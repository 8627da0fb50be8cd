"""A run through a plant's compiled loop (its adapter's ``compiled``), around the run's
generated C controller.

:func:`run_compiled` takes the arguments of :func:`fuzzkit.loop.python_loop.run` that the
compiled loop models; :func:`fuzzkit.loop.adapter.compiled_supports` says which plants have
one. The controller is the run's controller spec generated as C (double) and called by address
every period; the plant is reset in Python, then one compiled call runs every period. A spec
that adapts its gains gets its gain factor and stiffness estimate per period from the same
code (:mod:`fuzzkit.loop.compiled.adaptation_trace`).
"""

from __future__ import annotations

from collections.abc import Mapping

from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import adapter, compiled_plant, compiled_plants, compiled_supports
from fuzzkit.loop.compiled.common import controller_args
from fuzzkit.loop.compiled.generated_controller import (
    GeneratedController,
    load_generated_controller,
    run_controller_spec,
)
from fuzzkit.loop.faults import Faults
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.plants.contract import ContactPlant


def run_compiled(
    exp: Experiment,
    plant: str | ContactPlant = "arm6",
    controller: str = "pi",
    *,
    gains: Mapping[str, float] | None = None,
    rulebase: str = "macvicar_whelan",
    seed: int = 0,
    faults: Faults | None = None,
    duration_s: float | None = None,
    latency: tuple[int, int] | None = None,
    generated_controller: GeneratedController | None = None,
) -> RunResult:
    """Run ``exp`` on ``plant`` (a name, or a plant whose ``name`` is registered) with its
    compiled loop; same semantics as :func:`fuzzkit.loop.python_loop.run`.

    The controller is always generated C: ``generated_controller``
    (:func:`~fuzzkit.loop.compiled.generated_controller.load_generated_controller`), else
    the run's controller spec (:func:`~fuzzkit.loop.compiled.generated_controller.
    run_controller_spec` of ``exp``, ``controller``, ``gains``, ``rulebase``) generated,
    compiled (cached) and loaded. ``faults`` and ``latency`` default to the experiment's, as in
    the Python loop.

    Raises
    ------
    ConfigError
        For a plant without a compiled loop or an unknown controller.
        :class:`~fuzzkit.plants.contract.UnsupportedPlant` (a ConfigError) for a plant with
        objects or modes the kernel lacks (the Python loop runs it).
    ToolchainError
        No C compiler to build the controller.
    SimulationError
        When the planar arm's state becomes non-finite, as the Python plant raises it.
    """
    name = plant if isinstance(plant, str) else plant.name
    compiled = adapter(name).compiled if compiled_supports(name) else None
    if compiled is None:
        raise ConfigError(
            f"the compiled loop runs on {', '.join(compiled_plants())} (got {name!r}); "
            "use --loop python"
        )
    if isinstance(plant, str):
        plant = compiled_plant(plant)
    if generated_controller is None:
        generated_controller = load_generated_controller(
            run_controller_spec(exp, controller, gains, rulebase)
        )
    ctrl = controller_args(exp, generated_controller, seed, faults, duration_s, latency)
    result = compiled(exp, plant, ctrl, seed)
    if generated_controller.spec.adaptation.mode != "none":
        from fuzzkit.loop.compiled.adaptation_trace import record_adaptation

        record_adaptation(generated_controller, result)
    return result
