"""``fuzzkit stability --spec``: certify a controller spec as it ships.

From the spec: the controller kind, one axis's gains and set point, the front-end low-pass
(``sensor.lowpass_hz``, a second filter after the sensor's), the correction and step limits
(``region_n`` keeps the loop from reaching them), the surface method and the input roles. The
scenario gives the plant side: period (it must be the spec's), contact damping, the F/T
sensor's filter and noise. The inner loop is identified along task z and used for the axis
certified, as for every certificate (docs/stability.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from fuzzkit.analysis.region import SIGMA_MIN, Region, certify_region, effective_gains
from fuzzkit.analysis.schedule_certificate import (
    DEFAULT_RHO,
    RHO_STEPS,
    adaptation_model,
    scale_function,
)
from fuzzkit.control.spec import AxisSpec, ControllerSpec, role_ordered, with_gains
from fuzzkit.errors import ConfigError
from fuzzkit.loop.task import Experiment, with_spec


def spec_axis(spec: ControllerSpec, axis: str | None) -> AxisSpec:
    """The axis to certify: ``axis``, else the spec's z axis, else its only axis.

    Raises
    ------
    ConfigError
        ``axis`` is not one of the spec's, or none was given and the spec has several without z.
    """
    names = [a.axis for a in spec.axes]
    if axis is None:
        if "z" in names:
            axis = "z"
        elif len(names) == 1:
            axis = names[0]
        else:
            raise ConfigError(
                f"controller spec {spec.name!r} has axes {', '.join(names)}: say which one to "
                "certify with --axis"
            )
    for a in spec.axes:
        if a.axis == axis:
            return a
    raise ConfigError(
        f"controller spec {spec.name!r} has no axis {axis!r} (its axes: {', '.join(names)})"
    )


def spec_gains(spec: ControllerSpec, ax: AxisSpec) -> dict[str, float]:
    """The axis's gains as the certificate reads them."""
    gains = {"kp": ax.kp, "ki": ax.ki}
    if spec.kind == "fuzzy-pi" and ax.kx is not None:
        gains["kx"] = ax.kx
    return gains


def spec_experiment(exp: Experiment, spec: ControllerSpec, ax: AxisSpec) -> Experiment:
    """``exp`` with the certified axis's set point on its force-controlled z axis.

    Raises
    ------
    ConfigError
        The periods differ, or ``exp`` does not force-control z.
    """
    with_spec(exp, spec)  # checks the periods
    if not exp.selection[2]:
        raise ConfigError(f"scenario {exp.name} does not force-control z: nothing to certify on")
    if not ax.setpoint_n > 0.0:
        raise ConfigError(
            f"axis {ax.axis} of {spec.name!r} holds {ax.setpoint_n:g} N: the certificate is "
            "about a loop in contact, its set point must be > 0 N (choose another --axis)"
        )
    return replace(exp, setpoints=(exp.setpoints[0], exp.setpoints[1], ax.setpoint_n))


def certify_spec(
    exp: Experiment,
    spec: ControllerSpec,
    plant: str,
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    *,
    axis: str | None = None,
    fuzzy_region: float = 1.0,
    sigma_min: float = SIGMA_MIN,
    rho: float = DEFAULT_RHO,
) -> Region:
    """Certify ``spec``'s controller (one axis) on ``plant`` in the task ``exp``.

    A spec that adapts its gains is certified over every factor its adaptation can run at each
    stiffness, with the estimate within ``rho`` (:mod:`fuzzkit.analysis.schedule_certificate`);
    the model's ``adaptation`` says what was assumed and, for a schedule that is not certified
    in every cell, the largest estimate error of :data:`RHO_STEPS` it would be
    (``rho_needed``; None: not even an exact estimate).

    Raises
    ------
    ConfigError
        See :func:`spec_axis` and :func:`spec_experiment`.
    """
    region = _certify_spec(
        exp, spec, plant, stiffnesses_n_per_mm, latencies, axis, fuzzy_region, sigma_min, rho
    )
    ad = spec.adaptation
    if ad.mode == "none":
        return region
    model = adaptation_model(ad, rho, stiffnesses_n_per_mm)
    proved = all(c.certified for c in region.cells)
    model["certified_every_cell"] = proved
    if not proved and ad.mode == "stiffness-scheduled":
        needed = None
        for smaller in (r for r in RHO_STEPS if r < rho):
            trial = _certify_spec(
                exp, spec, plant, stiffnesses_n_per_mm, latencies, axis, fuzzy_region,
                sigma_min, smaller,
            )  # fmt: skip
            if all(c.certified for c in trial.cells):
                needed = smaller
                break
        model["rho_needed"] = needed
    region.model["adaptation"] = model
    return region


def _certify_spec(
    exp: Experiment,
    spec: ControllerSpec,
    plant: str,
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    axis: str | None,
    fuzzy_region: float,
    sigma_min: float,
    rho: float,
) -> Region:
    ax = spec_axis(spec, axis)
    task = spec_experiment(exp, spec, ax)
    rulebase: Any = "macvicar_whelan"
    if spec.kind == "fuzzy-pi":
        if spec.rulebase is None:
            raise ConfigError(f"controller spec {spec.name!r}: fuzzy-pi without a rule base")
        rulebase = role_ordered(spec, spec.rulebase)
    gains = spec_gains(spec, ax)
    source = spec.source.path if spec.source is not None else None
    deployed = {
        "spec": spec.name,
        "file": None if source is None else str(source),
        "axis": ax.axis,
        "surface": spec.surface.method,
        "assumed": False,
    }
    return certify_region(
        task,
        spec.kind,
        plant,
        stiffnesses_n_per_mm,
        latencies,
        gains=gains,
        rulebase=rulebase,
        fuzzy_region=fuzzy_region,
        sigma_min=sigma_min,
        surface=spec.surface,
        frontend_cutoff_hz=spec.sensor.lowpass_hz,
        limits_m=(spec.limits.step_m, spec.limits.correction_m),
        deployed=deployed,
        gain_scale=None if spec.adaptation.mode == "none" else scale_function(spec.adaptation, rho),
    )


def assumed(controller: str, gains: dict[str, float], rulebase: str) -> dict[str, Any]:
    """What ``fuzzkit stability`` certifies without ``--spec``, for the output."""
    g = effective_gains(controller, gains)[0]
    text = ", ".join(f"{k}={v:g}" for k, v in g.items() if k in ("kp", "ki", "kx"))
    what = f"{controller} ({text})"
    if controller == "fuzzy-pi":
        what += f" on {rulebase} (exact surface)"
    return {
        "assumed": True,
        "controller": what,
        "text": f"assumed controller: {what}, the scenario's set point and sensor filter, no "
        "front-end low-pass, no correction or step limit; give --spec SPEC to certify a "
        "controller spec as it ships",
    }


@dataclass(frozen=True)
class SpecCertifiedOver:
    """A gain-set predicate for ``fuzzkit tune --spec SPEC --certify``: the spec as it ships
    (its surface, rule base and input roles, front-end low-pass, limits, set points) with the
    candidate gains on every axis (:func:`~fuzzkit.control.spec.with_gains`, what tuning a spec
    tries), certified by :func:`certify_spec` in every cell of the grid, on every axis that
    holds a contact force (set point > 0 N: a 0 N axis is no loop in contact). Stops at the
    first axis that is not."""

    experiment: Experiment
    spec: ControllerSpec
    plant: str
    stiffnesses_n_per_mm: tuple[float, ...]
    latencies: tuple[tuple[int, int], ...]
    sigma_min: float = SIGMA_MIN

    def __call__(self, gains: Mapping[str, float]) -> bool:
        tuned = with_gains(self.spec, gains)
        grid = (self.stiffnesses_n_per_mm, self.latencies)
        held = [ax.axis for ax in tuned.axes if ax.setpoint_n > 0.0]
        return all(
            cell.certified
            for axis in held
            for cell in certify_spec(
                self.experiment, tuned, self.plant, *grid, axis=axis, sigma_min=self.sigma_min
            ).cells
        )
