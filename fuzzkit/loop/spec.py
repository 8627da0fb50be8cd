"""A closed-loop run as data (:class:`RunSpec`): what :func:`fuzzkit.loop.run.run_loop` takes, with
the experiment it runs on, and what ``fuzzkit simulate``, ``sweep`` and the report's grids
describe their runs with (plain picklable data: a sweep's workers get it as it is)."""

from __future__ import annotations

from dataclasses import dataclass

from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import compiled_supports

LOOPS = ("auto", "compiled", "python")
#: How the Python loop's reference controller evaluates a fuzzy-PI's surface: the ``exact``
#: engine (``auto``), the generated double lookup ``table``, or the rule base's generated ``c``
#: through ctypes. The compiled loop runs the generated controller, whose surface is the spec's.
FUZZY_IMPLS = ("auto", "exact", "table", "c")
#: Which controller runs: ``c``, the run's controller spec generated as C and run whole in the
#: compiled loop; ``python``, fuzzkit's reference controller in the Python loop; ``auto``: C
#: where the compiled loop runs (arm6, planar) and a C compiler exists, else the reference.
CONTROLLER_IMPLS = ("auto", "python", "c")


@dataclass(frozen=True, slots=True)
class RunSpec:
    """One closed-loop run, as data.

    ``stiffness_n_per_mm``: None keeps the experiment's own. ``latency``: ``(sensor, command)``
    delays in periods (None: the experiment's). ``fault``: a fault kind of
    :data:`fuzzkit.loop.faults.FAULTS`, seeded by ``seed`` (None: the experiment's).
    ``gains``: overrides of the default gains, as sorted ``(name, value)`` pairs;
    ``gains_label`` names where they came from (a file) for the table. ``loop``:
    ``compiled`` (arm6, planar), ``python``, or ``auto`` (compiled where supported).
    ``duration_s``: None runs the experiment's whole duration. ``controller_spec``: a
    controller spec file (``docs/controller.md``) whose controller runs instead of
    ``controller`` with ``gains`` (a scenario with a ``controller:`` runs its own).
    ``controller_impl``: ``auto``, ``c`` (the run's controller spec, given or built from the
    settings, generated as C and run in the compiled loop) or ``python`` (the reference
    controller in the Python loop); :data:`CONTROLLER_IMPLS`.
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
        """``compiled`` or ``python``: what ``auto`` means for this plant."""
        if self.loop not in LOOPS:
            raise ConfigError(f"unknown loop {self.loop!r} (expected {', '.join(LOOPS)})")
        if self.loop == "auto":
            reference = self.controller_impl == "python" or self.fuzzy_impl != "auto"
            return "compiled" if compiled_supports(self.plant) and not reference else "python"
        if self.loop == "compiled" and not compiled_supports(self.plant):
            raise ConfigError(
                f"the compiled loop does not model the {self.plant} plant (it runs on arm6 and "
                "planar); "
                "use --loop python"
            )
        return self.loop
