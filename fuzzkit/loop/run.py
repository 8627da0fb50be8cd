"""The closed loop's entry point: :func:`run_loop`, a run specification and its experiment in, a
:class:`~fuzzkit.loop.result.RunResult` out, and the one rule for which loop and which
controller implementation run it."""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any

from fuzzkit.errors import ConfigError
from fuzzkit.loop import python_loop
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import CONTROLLER_IMPLS, FUZZY_IMPLS, RunSpec
from fuzzkit.loop.task import Experiment
from fuzzkit.plants.contract import ContactPlant, UnsupportedPlant

if TYPE_CHECKING:
    from fuzzkit.control.controllers import Surface
    from fuzzkit.loop.generated import StepFunction


@lru_cache(maxsize=8)
def _exact_surface(rulebase: str) -> Any:
    return python_loop.load_surface(rulebase)


def run_loop(
    spec: RunSpec,
    exp: Experiment,
    plant: str | ContactPlant,
    *,
    step: tuple[StepFunction, str] | None = None,
    surface: Surface | None = None,
) -> RunResult:
    """Run ``spec`` on ``exp`` (its controller spec, stiffness and task resolved:
    :func:`fuzzkit.studies.batch.resolve`) and ``plant`` (a registered name, or a plant
    object whose ``name`` is registered); the one entry point of the closed loop.

    Every run executes the run's controller spec as ``fuzzkit compile`` generates it (C
    double; the generated Python without a C compiler): in the plant's compiled loop where
    its adapter has one, else in the Python loop (MuJoCo; a scenario the kernels lack, a run
    without a compiler: ``loop`` is then ``python (fallback: ...)``); ``controller_impl`` names
    the code (``controller_impl="python"``: the generated Python, in the Python loop). The
    reference controller runs only when asked for (``controller_impl="reference"``). A spec
    that adapts its gains runs its generated code too, with the code's gain factor and
    stiffness estimate recorded per period.

    ``step``: a step function and its label that take the generated controller's steps in
    place of the code opened in this process (the ROS 2 closed loop: the controller node, over
    the middleware). Such a run is the Python loop's, as ``loop="python"`` of the same spec
    with the code the function stands for.

    ``surface``: a fuzzy-PI's surface given as a Python function ``du = F(e, de)``. No code is
    generated from a function, so it runs on the reference controller only, asked for by name
    (``controller_impl="reference"``), and the run's ``controller_impl`` names the function.

    Raises
    ------
    ConfigError
        ``step`` with the reference controller, the compiled loop or an adapting spec; a
        ``surface`` without the reference controller, for PI, or with a ``fuzzy_impl``.
    """
    from fuzzkit.loop.faults import fault

    if spec.controller == "fuzzy-pi" and surface is None:  # what the loop needs, said first
        from fuzzkit.control.loop_rulebase import check_loop_rulebase, load_loop_rulebase

        cs = exp.controller_spec
        if cs is not None and cs.rulebase is not None:
            check_loop_rulebase(cs.rulebase, spec.rulebase)
        else:
            load_loop_rulebase(spec.rulebase)
    faults = fault(spec.fault or exp.fault, spec.seed)
    check_implementation(spec)
    loop = spec.resolved_loop()
    if surface is not None:
        _check_function_surface(spec)
    if step is not None:
        cs = exp.controller_spec
        if (
            spec.controller_impl == "reference"
            or spec.loop == "compiled"
            or (cs is not None and cs.adaptation.mode != "none")
        ):
            raise ConfigError(
                "a step function stands for the generated controller of a non-adapting spec "
                "in the Python loop (not the reference, not the compiled loop)"
            )
        return _run_generated_python_loop(spec, exp, plant, faults, "", step)
    if spec.controller_impl == "reference":
        return _run_reference(spec, exp, plant, faults, "", surface)
    if loop == "compiled":
        try:
            return _run_generated(spec, exp, plant, faults)
        except _Fallback as exc:
            if spec.loop == "compiled":
                # the loop asked for cannot run it (a ConfigError: exit 2 on the command line)
                raise UnsupportedPlant(f"{exc}; use --loop python") from exc
            fallback = f" (fallback: {exc})"
    else:
        fallback = ""  # a plant without a compiled loop (mujoco), or the Python loop asked for
    return _run_generated_python_loop(spec, exp, plant, faults, fallback)


def check_implementation(spec: RunSpec) -> None:
    """The one rule for which controller runs, checked: the spec's generated controller
    (``controller_impl`` ``auto``, ``c`` or ``python``), or the reference when asked for by
    name (``reference``; a ``fuzzy_impl`` chooses the reference's surface, so it asks for the
    reference too). ``loop`` names the loop, never the controller.

    Raises
    ------
    ConfigError
        An unknown implementation, or a ``fuzzy_impl`` without the reference.
    """
    impl = spec.fuzzy_impl
    if impl not in FUZZY_IMPLS:
        raise ConfigError(f"unknown fuzzy implementation {impl!r} (expected {FUZZY_IMPLS})")
    if spec.controller_impl not in CONTROLLER_IMPLS:
        raise ConfigError(
            f"unknown controller implementation {spec.controller_impl!r} "
            f"(expected {', '.join(CONTROLLER_IMPLS)})"
        )
    if impl != "auto" and spec.controller_impl != "reference":
        raise ConfigError(
            f"--fuzzy-impl {impl} chooses the reference controller's surface, and this run "
            "executes the spec's generated controller: add --controller-impl reference"
        )


def _check_function_surface(spec: RunSpec) -> None:
    """A surface given as a function runs where it can: the reference's fuzzy-PI."""
    name = "a surface given as a Python function"
    if spec.controller != "fuzzy-pi":
        raise ConfigError(
            f"{name} is a fuzzy-PI's surface; this run's controller is {spec.controller}"
        )
    if spec.controller_impl != "reference":
        raise ConfigError(
            f"{name} has no generated code (the {spec.controller_impl} controller implementation "
            "runs what `fuzzkit compile` emits from a rule base): run it on the reference "
            "controller (controller_impl='reference'), or give the rule base by name or path"
        )
    if spec.fuzzy_impl != "auto":
        raise ConfigError(f"{name} is the surface: leave fuzzy_impl at auto, not {spec.fuzzy_impl}")


class _Fallback(Exception):
    """Why the compiled loop cannot take a run the Python loop can."""


def _run_generated_python_loop(
    spec: RunSpec,
    exp: Experiment,
    plant: Any,
    faults: Any,
    fallback: str,
    step: tuple[StepFunction, str] | None = None,
) -> RunResult:
    """``spec`` with the run's generated controller (C, or the generated Python: asked for,
    or without a compiler) in the Python loop; ``loop`` says so, with ``fallback`` (why the
    compiled loop could not take it)."""
    from fuzzkit.loop.generated import run_controller

    ctrl = run_controller(
        exp, spec.controller, dict(spec.gains), spec.rulebase, spec.seed, faults, spec.latency,
        spec.controller_impl, step,
    )  # fmt: skip
    result = python_loop.run(exp, plant, ctrl.kind, hybrid=ctrl, seed=spec.seed, faults=faults,
                 latency=spec.latency, duration_s=spec.duration_s)  # fmt: skip
    result.loop += fallback
    return result


def _run_reference(
    spec: RunSpec,
    exp: Experiment,
    plant: Any,
    faults: Any,
    fallback: str,
    function: Surface | None = None,
) -> RunResult:
    """``spec`` in the Python loop, on the reference controller (its fuzzy-PI on ``function``
    when given: a surface given as a Python function)."""

    surface: Any = None
    label = "pi (python)"
    cs = exp.controller_spec
    if function is not None:
        surface = function
        name = getattr(function, "__qualname__", None) or type(function).__name__
        label = f"surface given as the Python function {name} (python)"
    elif spec.controller == "fuzzy-pi":
        impl = spec.fuzzy_impl
        if cs is not None and impl in ("auto", "exact"):
            surface, label = _spec_reference_surface(cs, impl, spec.rulebase)
        elif impl in ("auto", "exact"):
            surface = _exact_surface(spec.rulebase)
            label = f"exact engine {spec.rulebase} (python)"
        else:
            if cs is not None:
                _require_positional_roles(cs, impl)
            if impl == "table":
                from fuzzkit.control.controllers import lookup_table_surface
                from fuzzkit.loop.compiled.table import load_table, table_arrays

                table = load_table(spec.rulebase)
                surface = lookup_table_surface(table)
                label = table_arrays(table).label + " (python)"
            else:
                from fuzzkit.loop.compiled.generated_c import c_surface

                surface = c_surface(spec.rulebase)
                label = f"{surface.__name__} (python loop)"
    if exp.controller_spec is not None:
        label = f"spec {exp.controller_spec.name}: reference controller, {label}"
    else:
        label = f"reference controller, {label}"
    result = python_loop.run(
        exp,
        plant,
        spec.controller,
        gains=dict(spec.gains),
        surface=surface,
        seed=spec.seed,
        faults=faults,
        latency=spec.latency,
        duration_s=spec.duration_s,
        controller_impl=label,
    )
    result.loop += fallback
    return result


def _spec_reference_surface(cs: Any, impl: str, rulebase: str) -> tuple[Any, str]:
    """A controller spec's surface on the reference controller, in the spec's input roles:
    its own (``auto``: the exact engine, or a ``table`` spec's lookup table) or the exact
    engine (``exact``), with the run's label."""
    from fuzzkit.control.loop_rulebase import exact_surface
    from fuzzkit.control.spec import surface_inputs
    from fuzzkit.loop.controller_code import spec_surface

    if impl == "auto" and cs.surface.method == "table":
        return spec_surface(cs), "the spec's lookup table (python)"
    return exact_surface(cs.rulebase, surface_inputs(cs, cs.rulebase)), (
        f"exact engine {rulebase} (python)"
    )


def _require_positional_roles(cs: Any, impl: str) -> None:
    """``--fuzzy-impl table|c`` builds the rule base's own table or C, which take its inputs in
    file order: refuse a spec whose ``inputs:`` maps them the other way round."""
    from fuzzkit.control.loop_rulebase import POSITIONAL_ROLES
    from fuzzkit.control.spec import surface_inputs

    if surface_inputs(cs, cs.rulebase) != POSITIONAL_ROLES:
        raise ConfigError(
            f"--fuzzy-impl {impl} evaluates rule base {cs.rulebase.name}'s inputs in file "
            f"order, and controller spec {cs.name!r} maps them the other way round (inputs: "
            f"{', '.join(cs.inputs)}): leave out --fuzzy-impl (the spec's own surface runs)"
        )


def _run_generated(spec: RunSpec, exp: Experiment, plant: Any, faults: Any) -> RunResult:
    """``spec`` with the run's generated C controller in the compiled loop.

    Raises
    ------
    _Fallback
        The compiled loop cannot run it (a plant mode the kernel lacks, no C compiler); the
        caller decides whether the Python loop may.
    """
    from fuzzkit.errors import ToolchainError
    from fuzzkit.loop.compiled.generated_controller import (
        load_generated_controller,
        run_controller_spec,
    )
    from fuzzkit.loop.compiled_loop import run_compiled

    ctl_spec = run_controller_spec(exp, spec.controller, dict(spec.gains), spec.rulebase)
    try:
        generated = load_generated_controller(ctl_spec)
    except ToolchainError as exc:
        if spec.controller_impl == "c":
            raise ConfigError(
                f"--controller-impl c runs the generated C controller and {exc}"
            ) from exc
        raise _Fallback(f"the compiled loop runs the generated C controller and {exc}") from exc
    try:
        return run_compiled(
            exp,
            plant,
            seed=spec.seed,
            faults=faults,
            latency=spec.latency,
            duration_s=spec.duration_s,
            generated_controller=generated,
        )
    except UnsupportedPlant as exc:
        raise _Fallback(str(exc)) from exc
