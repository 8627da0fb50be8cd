"""The tuning problem: the cases a gain set is priced on (experiment x stiffness x latency) and
how per-case costs aggregate into the cost of a gain set.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from fuzzkit.control.controllers import Surface
from fuzzkit.errors import ConfigError
from fuzzkit.loop.adapter import make_plant
from fuzzkit.loop.spec import CONTROLLER_IMPLS, LOOPS
from fuzzkit.plants.arm6 import Arm6Plant
from fuzzkit.plants.contract import ContactPlant
from fuzzkit.studies.e3_arm6 import make_e3_arm6_plant, resolve
from fuzzkit.studies.experiments import DEFAULT_GAINS, Experiment, experiment, with_stiffness
from fuzzkit.studies.tuning.cost import CostWeights
from fuzzkit.studies.tuning.spaces import SPACES, GainSpace

#: Environment stiffnesses (N/mm) tuned over by default: half and twice the experiments' own
#: 10 N/mm, so the optimum tolerates a softer or stiffer part than the one programmed for.
DEFAULT_STIFFNESSES_N_PER_MM: tuple[float, ...] = (5.0, 10.0, 20.0)

#: Simulated time per experiment while tuning (s). First contact is at about 1.9 s (E1) and
#: 1.0 s (E2, E3); each horizon keeps the contact transient and 1-4 s of holding or sliding,
#: where the gains make the difference, and drops the rest of the path.
TUNING_HORIZON_S: dict[str, float] = {"E1": 3.5, "E2": 4.5, "E3": 6.0, "press": 1.5}


PlantSpec = str | Callable[[], ContactPlant]
SurfaceSpec = str | Surface


def function_surface_impl(controller_impl: str, loop: str) -> str:
    """The controller implementation that prices a surface given as a Python function: the
    reference controller (no code is generated from a function), asked for by name here so
    that every run says so.

    Raises
    ------
    ConfigError
        The generated controller (``c``, ``python``) or the compiled loop asked for.
    """
    if controller_impl in ("c", "python"):
        raise ConfigError(
            f"--controller-impl {controller_impl} runs the generated controller, of a rule "
            "base given by name or path (a surface given as a function has no code; it runs "
            "on the reference controller)"
        )
    if loop == "compiled":
        raise ConfigError(
            "the compiled loop runs the generated controller, and a surface given as a "
            "function has none (it runs on the reference controller): use loop='python'"
        )
    return "reference"


@dataclass(frozen=True, slots=True)
class TuningCase:
    """One case a gain set is priced on: an experiment at a stiffness and a latency.

    ``label`` is the key of :attr:`TuneResult.case_costs` (``E1@10N/mm``, with ``@lat1:1``
    appended when several latencies are tuned over); ``latency`` is None for the experiment's
    own.
    """

    label: str
    experiment: str
    stiffness_n_per_mm: float
    latency: tuple[int, int] | None


@dataclass(frozen=True)
class TuningProblem:
    """Everything needed to price a gain set; picklable, so worker processes get a copy.

    Build it with :meth:`build`. ``cases`` are (experiment, stiffness) pairs; ``groups[i]`` is
    the index in ``experiments`` of case i's experiment.
    """

    controller: str
    experiments: tuple[str, ...]
    cases: tuple[Experiment, ...]
    labels: tuple[str, ...]
    groups: tuple[int, ...]
    horizons: tuple[float, ...]
    plant: PlantSpec
    surface: SurfaceSpec | None
    space: GainSpace
    fixed: dict[str, float]
    weights: CostWeights
    noise_seed: int
    stiffnesses_n_per_mm: tuple[float, ...] | None
    #: ``(sensor, command)`` delay of each case, in periods (parallel to ``cases``; None: the
    #: experiment's own)
    case_latencies: tuple[tuple[int, int] | None, ...] = ()
    latencies: tuple[tuple[int, int], ...] | None = None
    #: ``auto`` (the compiled loop where the plant has one), ``compiled`` or ``python``
    loop: str = "auto"
    #: which code runs each candidate's controller spec (``fuzzkit.loop.spec.CONTROLLER_IMPLS``:
    #: the generated C or Python, or the reference when asked for)
    controller_impl: str = "auto"
    #: what each case is (parallel to ``cases``)
    case_keys: tuple[TuningCase, ...] = ()
    #: cases that run the paper's 3-D E3 on its own arm6 world (:mod:`fuzzkit.studies.e3_arm6`)
    paper_e3_cases: tuple[bool, ...] = ()

    def latency_of(self, case: int) -> tuple[int, int] | None:
        """The latency of case ``case`` (None: its experiment's own)."""
        return self.case_latencies[case] if self.case_latencies else None

    @classmethod
    def build(
        cls,
        experiments: Sequence[str | Experiment],
        controller: str = "pi",
        rulebase: SurfaceSpec = "macvicar_whelan",
        plant: PlantSpec = "planar",
        stiffnesses_n_per_mm: Sequence[float] | None = DEFAULT_STIFFNESSES_N_PER_MM,
        *,
        space: GainSpace | None = None,
        weights: CostWeights = CostWeights(),
        horizon_s: float | None = None,
        noise_seed: int = 0,
        latencies: Sequence[tuple[int, int]] | None = None,
        loop: str = "auto",
        controller_impl: str = "auto",
    ) -> TuningProblem:
        """Check the arguments and assemble the problem (arguments as for :func:`tune`).

        Raises
        ------
        ConfigError
            Unknown controller, experiment, plant or rule base; no experiments; a stiffness or
            horizon that is not a positive finite number.
        """
        if controller not in SPACES:
            raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
        if not experiments:
            raise ConfigError("tuning needs at least one experiment")
        # A name resolves as ``simulate`` resolves it: E3 on arm6 is the paper's 3-D E3.
        paper_e3 = [
            isinstance(e, str) and plant == "arm6" and e.upper() == "E3" for e in experiments
        ]
        exps = [
            (resolve(e, str(plant))[0] if paper else experiment(e)) if isinstance(e, str) else e
            for e, paper in zip(experiments, paper_e3, strict=True)
        ]
        names = tuple(e.name for e in exps)
        if len(set(names)) != len(names):
            raise ConfigError(f"experiments listed twice: {', '.join(names)}")
        if stiffnesses_n_per_mm is not None:
            ks = tuple(float(k) for k in stiffnesses_n_per_mm)
            if not ks or not all(math.isfinite(k) and k > 0.0 for k in ks):
                raise ConfigError(
                    f"stiffnesses must be positive finite numbers in N/mm (got {list(ks)})"
                )
        else:
            ks = None
        if horizon_s is not None and not (math.isfinite(horizon_s) and horizon_s > 0.0):
            raise ConfigError(f"horizon must be > 0 s (got {horizon_s})")
        if isinstance(plant, str):
            make_plant(plant)  # an unknown name fails here, not in a worker
        surface: SurfaceSpec | None = None
        if controller == "fuzzy-pi":
            if isinstance(rulebase, str):
                from fuzzkit.control.loop_rulebase import load_loop_rulebase

                load_loop_rulebase(rulebase)  # a bad or unfit rule base fails here
            surface = rulebase
        cases: list[Experiment] = []
        labels: list[str] = []
        groups: list[int] = []
        horizons: list[float] = []
        stiffness_of: list[float] = []
        for gi, exp in enumerate(exps):
            h = horizon_s or TUNING_HORIZON_S.get(exp.name, exp.scenario.duration_s)
            h = min(h, exp.scenario.duration_s)
            for k in ks if ks is not None else (None,):
                if k is None:
                    cases.append(exp)
                    k_mm = exp.scenario.contact.stiffness_n_per_m / 1e3
                else:
                    cases.append(with_stiffness(exp, k * 1e3))
                    k_mm = k
                labels.append(f"{exp.name}@{k_mm:g}N/mm")
                stiffness_of.append(k_mm)
                groups.append(gi)
                horizons.append(h)
        lats = None if latencies is None else tuple((int(a), int(b)) for a, b in latencies)
        if lats is not None and (not lats or any(min(pair) < 0 for pair in lats)):
            raise ConfigError(f"latencies must be (sensor, command) pairs >= 0 (got {lats})")
        if loop not in LOOPS:
            raise ConfigError(f"unknown loop {loop!r} (expected {', '.join(LOOPS)})")
        if controller_impl not in CONTROLLER_IMPLS:
            raise ConfigError(
                f"unknown controller implementation {controller_impl!r} "
                f"(expected {', '.join(CONTROLLER_IMPLS)})"
            )
        if surface is not None and not isinstance(surface, str):
            controller_impl = function_surface_impl(controller_impl, loop)
        case_lats: tuple[tuple[int, int] | None, ...]
        if lats is not None:
            n_cases = len(cases)
            cases = [c for c in cases for _ in lats]
            labels = (
                [f"{lab}@lat{a}:{b}" for lab in labels for a, b in lats]
                if len(lats) > 1
                else labels
            )
            groups = [g for g in groups for _ in lats]
            horizons = [h for h in horizons for _ in lats]
            stiffness_of = [k for k in stiffness_of for _ in lats]
            case_lats = tuple(pair for _ in range(n_cases) for pair in lats)
        else:
            case_lats = tuple(None for _ in cases)  # each experiment's own latency
        paper_cases = tuple(paper_e3[g] for g in groups)
        keys = tuple(
            TuningCase(lab, names[g], k, lat)
            for lab, g, k, lat in zip(labels, groups, stiffness_of, case_lats, strict=True)
        )
        sp = space or SPACES[controller]
        fixed = {k: v for k, v in DEFAULT_GAINS[controller].items() if k not in sp.names}
        return cls(
            controller=controller,
            experiments=names,
            cases=tuple(cases),
            labels=tuple(labels),
            groups=tuple(groups),
            horizons=tuple(horizons),
            plant=plant,
            surface=surface,
            space=sp,
            fixed=fixed,
            weights=weights,
            noise_seed=noise_seed,
            stiffnesses_n_per_mm=ks,
            case_latencies=case_lats,
            latencies=lats,
            loop=loop,
            controller_impl=controller_impl,
            case_keys=keys,
            paper_e3_cases=paper_cases,
        )

    def plant_of(self, case: int) -> Arm6Plant | None:
        """A fresh plant for case ``case`` when it needs its own world (the paper's E3 on
        arm6), else None: the problem's ``plant``."""
        if self.paper_e3_cases and self.paper_e3_cases[case]:
            return make_e3_arm6_plant()
        return None

    def full_gains(self, gains: Mapping[str, float]) -> dict[str, float]:
        """``gains`` completed with the fixed entries (output limits) of the defaults."""
        out = dict(self.fixed)
        out.update(gains)
        return out

    def experiment_costs(self, case_costs: Sequence[float]) -> tuple[float, ...]:
        """Per-experiment costs: the mean over each experiment's stiffness cases."""
        sums = [0.0] * len(self.experiments)
        counts = [0] * len(self.experiments)
        for g, c in zip(self.groups, case_costs, strict=True):
            sums[g] += c
            counts[g] += 1
        return tuple(s / n for s, n in zip(sums, counts, strict=True))

    def aggregate(self, case_costs: Sequence[float]) -> float:
        """The cost of a gain set: mean of the per-experiment costs."""
        per = self.experiment_costs(case_costs)
        return float(sum(per) / len(per))

    @property
    def plant_name(self) -> str:
        """A name for the plant, for messages and provenance."""
        if isinstance(self.plant, str):
            return self.plant
        return str(getattr(self.plant, "__name__", type(self.plant).__name__))

    @property
    def rulebase_name(self) -> str | None:
        """The rule base name or path (None for PI or a surface given as a function)."""
        return self.surface if isinstance(self.surface, str) else None
