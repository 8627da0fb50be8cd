"""Optimal gains: PI ``Kp, Ki`` and fuzzy-PI scaling factors ``Kp, Ki, Kx`` by simulation.

The paper set its scaling factors "by trial and error" (sec. 3.2.4). Here they minimise a
documented closed-loop cost over one or more experiments and several environment stiffnesses at
once (a robust optimum, not one tuned to a single surface).

Cost (:func:`run_cost`, dimensionless, lower is better), per run from the first contact on::

    J = ITAE + w_os * overshoot + w_peak * excess_peak + w_trip * tripped + w_loss * loss

* ``ITAE = sum_axes  integral (t - t0) |f_d - f| dt / (F * T^2 / 2)``: the time-weighted mean of
  the true force error over the controlled axes, relative to ``F`` = the experiment's largest
  set point (at least 1 N); ``T`` is the time from first contact to the end of the horizon.
  Weighting by time forgives the unavoidable impact transient and punishes slow settling and a
  steady error.
* ``overshoot``: largest excursion past each non-zero set point, as a fraction of it (summed).
* ``excess_peak``: how far the largest force exceeds the experiment's safety limit, as a
  fraction of the limit; ``tripped`` is 1 when the safety limit tripped the controller.
* ``loss``: fraction of the time after first contact spent without contact.
* A run that never touches anything, or produces non-finite numbers, costs ``w_none`` (10).

The cost of a gain set is the mean over every (experiment, stiffness) case, i.e. the mean over
experiments of each experiment's mean over the stiffnesses.

Search (:func:`optimise`): gains are searched as ``log10`` values within bounds
(:data:`SPACES`), because good gains span decades across stiffnesses. Stage 1 is
``scipy.optimize.differential_evolution`` (seeded Latin-hypercube population holding the default
gains, ``updating="deferred"``, ``vectorized`` so each generation is one batch that a process
pool evaluates in parallel); stage 2 is a bounded compass (pattern) search around the best
point, whose ``2 * dims`` trial points per iteration also run in parallel. Both stages minimise
the cost plus ``PENALTY`` times how much worse than the default gains a candidate is on each
experiment, which steers the search towards candidates the final choice may return.
``budget`` caps the number of gain sets simulated, the default gains included. The result is
the cheapest *admissible* gain set found: by default (``admit="case"``) one that is no worse
than the default gains on *every case*, i.e. every (experiment, stiffness) pair it was tuned
for, so robust gains never trade the nominal stiffness away for a stiffer one; with
``admit="experiment"`` one no worse on each experiment's mean over the stiffnesses (a
compromise: it may be worse at some stiffness, and the CLI says by how much). The defaults
themselves are admissible, so this never fails; when nothing beats them, they are returned
and :attr:`TuneResult.kept_defaults` says so, with the cheapest candidate that was refused.

Speed: experiments are simulated over short horizons (:data:`TUNING_HORIZON_S`: first contact
plus the transient that the gains decide), and every candidate runs the generated controller
(compiled once per structure, its gains set as run-time parameters), in the compiled loop where
the plant has one.

Determinism: the same arguments and ``seed`` give the same gains for any number of workers (the
simulations are deterministic, the pool preserves order, the optimiser is seeded).

Modules, one idea each: :mod:`~fuzzkit.studies.tuning.cost` (the cost of one run),
:mod:`~fuzzkit.studies.tuning.spaces` (searched gains and bounds),
:mod:`~fuzzkit.studies.tuning.problem` (the cases and how their costs aggregate),
:mod:`~fuzzkit.studies.tuning.pricing` (simulating and costing a gain set, in workers too),
:mod:`~fuzzkit.studies.tuning.admission` (which candidates may be returned),
:mod:`~fuzzkit.studies.tuning.optimiser` (the search and :func:`tune`),
:mod:`~fuzzkit.studies.tuning.result` (:class:`TuneResult`). This package re-exports their
public names.
"""

from fuzzkit.studies.batch import default_workers
from fuzzkit.studies.tuning.admission import ADMIT_RULES, PENALTY, Evaluation
from fuzzkit.studies.tuning.cost import CostWeights, run_cost
from fuzzkit.studies.tuning.optimiser import Progress, optimise, progress_callback, tune
from fuzzkit.studies.tuning.pricing import CaseRunner, evaluate_gains
from fuzzkit.studies.tuning.problem import (
    DEFAULT_STIFFNESSES_N_PER_MM,
    TUNING_HORIZON_S,
    PlantSpec,
    SurfaceSpec,
    TuningCase,
    TuningProblem,
)
from fuzzkit.studies.tuning.result import TuneResult
from fuzzkit.studies.tuning.spaces import SPACES, GainSpace

__all__ = [
    "ADMIT_RULES",
    "DEFAULT_STIFFNESSES_N_PER_MM",
    "PENALTY",
    "SPACES",
    "TUNING_HORIZON_S",
    "CaseRunner",
    "CostWeights",
    "Evaluation",
    "GainSpace",
    "PlantSpec",
    "Progress",
    "SurfaceSpec",
    "TuneResult",
    "TuningCase",
    "TuningProblem",
    "default_workers",
    "evaluate_gains",
    "optimise",
    "progress_callback",
    "run_cost",
    "tune",
]
