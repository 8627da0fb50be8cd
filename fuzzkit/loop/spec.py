"""A closed-loop run as data (:class:`RunSpec`): what :func:`fuzzkit.loop.run.run_loop` takes, with
the experiment it runs on, and what ``fuzzkit simulate``, ``sweep`` and the report's grids
describe their runs with (plain picklable data: a sweep's workers get it as it is)."""

from __future__ import annotations

from dataclasses import dataclass

from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import compiled_plants, compiled_supports

LOOPS = ("auto", "compiled", "python")
#: How the reference controller evaluates a fuzzy-PI's surface (with ``controller_impl
#: "reference"`` only): the ``exact`` engine (``auto``), the generated double lookup ``table``,
#: or the rule base's generated ``c`` through ctypes. Every other run executes the generated
#: controller, whose surface is the spec's.
FUZZY_IMPLS = ("auto", "exact", "table", "c")
#: Which controller runs. ``auto``: the run's controller spec as ``fuzzkit compile`` generates
#: it, C (double) where a C compiler exists, else the generated Python; ``c``: the generated C
#: (refused without a compiler); ``python``: the generated Python (in the Python loop);
#: ``reference``: fuzzkit's reference controller (in the Python loop), only when asked for.
CONTROLLER_IMPLS = ("auto", "c", "python", "reference")
#: The implementations the compiled loops run (they call the generated C by address).
COMPILED_IMPLS = ("auto", "c")


@dataclass(frozen=True, slots=True)
class RunSpec:
    """One closed-loop run, as data.

    ``stiffness_n_per_mm``: None keeps the experiment's own. ``latency``: ``(sensor, command)``
    delays in periods (None: the experiment's). ``fault``: a fault kind of
    :data:`fuzzkit.loop.faults.FAULTS`, seeded by ``seed`` (None: the experiment's).
    ``gains``: overrides of the default gains, as sorted ``(name, value)`` pairs;
    ``gains_label`` names where they came from (a file) for the table. ``loop``:
    ``compiled`` (arm6, planar), ``python``, or ``auto`` (compiled where supported); it names
    the loop, never the controller.
    ``duration_s``: None runs the experiment's whole duration. ``controller_spec``: a
    controller spec file (``docs/controller.md``) whose controller runs instead of
    ``controller`` with ``gains`` (a scenario with a ``controller:`` runs its own).
    ``controller_impl``: which code runs the run's controller spec (given, or built from the
    settings), :data:`CONTROLLER_IMPLS`: the generated C or Python, or the reference when
    asked for. ``fuzzy_impl``: the reference controller's surface, :data:`FUZZY_IMPLS`.
    """

    experiment: str
    controller: str = "fuzzy-pi"
    plant: str = "arm6"
    stiffness_n_per_mm: float | None = None
    latency: tuple[int, int] | None = None
    seed: int = 0
    gains: tuple[tuple[str, float], ...] = ()
    gains_label: str = "default"
    rulebase: str = "macvicar_whelan"
    loop: str = "auto"
    duration_s: float | None = None
    fuzzy_impl: str = "auto"
    fault: str | None = None
    controller_spec: str | None = None
    controller_impl: str = "auto"

    def resolved_loop(self) -> str:
        """``compiled`` or ``python``: what ``auto`` means for this plant and implementation
        (the compiled loop where the plant's adapter has one and the controller is the
        generated C, the Python loop otherwise).

        Raises
        ------
        ConfigError
            An unknown loop, or ``compiled`` for a plant without a compiled loop or an
            implementation it does not run.
        """
        if self.loop not in LOOPS:
            raise ConfigError(f"unknown loop {self.loop!r} (expected {', '.join(LOOPS)})")
        compiled_impl = self.controller_impl in COMPILED_IMPLS
        if self.loop == "auto":
            return "compiled" if compiled_supports(self.plant) and compiled_impl else "python"
        if self.loop == "compiled" and not compiled_supports(self.plant):
            raise ConfigError(
                f"the compiled loop does not model the {self.plant} plant (it runs on "
                f"{' and '.join(compiled_plants())}); use --loop python"
            )
        if self.loop == "compiled" and not compiled_impl:
            raise ConfigError(
                f"--controller-impl {self.controller_impl} runs in the Python loop (the "
                "compiled loop runs the generated C): leave out --loop compiled"
            )
        return self.loop
