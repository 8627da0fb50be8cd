"""The certified region: every cell of a stiffness x latency grid, certified or not, with the
model it was certified for (the JSON of ``fuzzkit stability``)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np

from fuzzkit.analysis.certificate import MIN_MARGIN, FloatArray, certify
from fuzzkit.analysis.equilibrium import (
    Equilibrium,
    ZeroSet,
    fuzzy_equilibrium,
    pi_equilibrium,
    zero_set,
)
from fuzzkit.analysis.fuzzy_bounds import StructureError, gradient_bounds, phi_bounds
from fuzzkit.analysis.inner_loop import InnerLoop, identify
from fuzzkit.analysis.invariant_region import level_set, validity_slabs
from fuzzkit.analysis.loop_model import AxisLoop, noise_std, vertex_matrices
from fuzzkit.analysis.rest_points import RestProof, prove_exact, prove_table
from fuzzkit.analysis.surface_enclosure import why_unsupported
from fuzzkit.analysis.surface_source import SurfaceSource, surface_source
from fuzzkit.control.names import KINDS as CONTROLLERS
from fuzzkit.control.spec import EXACT, Surface
from fuzzkit.errors import ConfigError
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.task import Experiment
from fuzzkit.studies.experiments import DEFAULT_GAINS
from fuzzkit.studies.outcome import BAND_N

#: Default lower end of the contact sector: the certificate holds while the spring-damper force
#: the contact would have stays above (1 - 1/SIGMA_MIN) times the set point (docs/stability.md).
SIGMA_MIN = 0.1

#: A certified cell must also keep the force's noise-driven standard deviation, predicted by
#: the nominal model, below this share of the band (a stable loop can still amplify the
#: sensor noise past it: 4x the default PI at 10 N/mm without latency, about 1 N).
NOISE_SHARE = 0.5

METHOD = (
    "common quadratic Lyapunov function over the vertices of the loop's parameter box "
    "(contact sector, fuzzy gain, inner-loop uncertainty), LMI solved by Clarabel, "
    f"verified in numpy with a decay margin >= {MIN_MARGIN:g} per period"
)


@dataclass(frozen=True, slots=True)
class FuzzyPart:
    """How the fuzzy surface enters the linear model: ``phi`` on both terms (PI-like
    structure), ``phi`` on the error term and ``phi_de`` on the change of error (gradient
    bounds around the rest point), or ``none`` (no rest point: nothing to certify).
    ``zeros``: where ``F(x, 0) = 0`` (the rest points, :mod:`fuzzkit.analysis.equilibrium`)."""

    kind: str  # "phi" | "gradient" | "none"
    phi: tuple[float, float]
    phi_de: tuple[float, float] | None
    rho: float
    zeros: ZeroSet
    details: dict[str, Any] = field(default_factory=dict)
    #: the sound proof that no other rest point lies on the line de = 0
    #: (:mod:`fuzzkit.analysis.rest_points`); a string: why there is none
    rest: RestProof | str = "not computed"
    #: the rule base (role order) and surface the bounds were taken on, to take them again
    #: on a smaller box (:func:`local_parts`)
    source: tuple[RuleBase, Surface] | None = None


def fuzzy_part(rulebase: str | RuleBase, rho: float = 1.0, surface: Surface = EXACT) -> FuzzyPart:
    """The bounds of the rule base's surface, evaluated as ``surface`` (its inputs in role
    order; a name or path: by position), over a box of half-width ``rho`` around the loop's
    rest point, exact on the table :mod:`fuzzkit.analysis.surface_source` gives: the PI-like
    factorisation where it holds, else the gradient bounds around the rest point nearest the
    origin."""
    from fuzzkit.control.loop_rulebase import load_loop_rulebase

    rb = load_loop_rulebase(rulebase) if isinstance(rulebase, str) else rulebase
    return _fuzzy_part(rb, rho, surface)


@lru_cache(maxsize=16)
def _rest_proof(rb: RuleBase, surface: Surface) -> RestProof | str:
    """No other rest point on the whole line de = 0, proven on the deployed surface."""
    source = surface_source(rb, surface)
    if source.covers_deployed:
        return prove_table(source.table, -1.0, 1.0)
    why = why_unsupported(source.rulebase)
    if why is not None:
        return f"no sound bound of the exact surface: {why}"
    return prove_exact(source.rulebase, -1.0, 1.0)


@lru_cache(maxsize=256)
def _fuzzy_part(rb: RuleBase, rho: float, surface: Surface) -> FuzzyPart:
    part = _fuzzy_bounds(rb, rho, surface)
    return replace(part, rest=_rest_proof(rb, surface), source=(rb, surface))


#: The boxes a failed cell is tried on again, as shares of its box's half-width.
LOCAL_SHARES = tuple(2.0 ** (-k / 2) for k in range(1, 11))
#: At most this many of them are searched for a Lyapunov function.
LOCAL_TRIES = 2


def local_parts(fuzzy: FuzzyPart) -> Iterator[FuzzyPart]:
    """The bounds on boxes around the rest point smaller than ``fuzzy``'s, largest first."""
    if fuzzy.source is None:
        return
    rb, surface = fuzzy.source
    seen = fuzzy.rho
    for share in LOCAL_SHARES:
        part = _fuzzy_part(rb, share * fuzzy.rho, surface)
        if part.rho < seen:  # the box covers whole table cells: skip repeats
            seen = part.rho
            yield part


def _fuzzy_bounds(rb: RuleBase, rho: float, surface: Surface) -> FuzzyPart:
    source = surface_source(rb, surface)
    t = source.table
    zeros = zero_set(source.on_error_axis, tuple(float(b) for b in t.bp0))
    try:
        b = phi_bounds(t.bp0, t.bp1, t.values, t.splits, rho)
    except StructureError as exc:
        centre = zeros.rest_point
        if centre is None:
            return FuzzyPart(
                "none", (0.0, 0.0), None, 0.0, zeros, {"why": str(exc), **_surface_details(source)}
            )
        g = gradient_bounds(t.bp0, t.bp1, t.values, t.splits, rho, centre)
        return FuzzyPart(
            "gradient",
            g.a_range,
            g.b_range,
            g.rho,
            zeros,
            {
                "method": g.method,
                "why": str(exc),
                "around_scaled_error": g.centre,
                "dF_de": list(g.a_range),
                "dF_dde": list(g.b_range),
                **_surface_details(source),
            },
        )
    return FuzzyPart(
        "phi",
        (b.low, b.high),
        None,
        b.rho,
        zeros,
        {
            "method": b.method,
            "phi": [b.low, b.high],
            "small_signal_phi": b.small_signal,
            "rounding_residual": b.residual,
            **_surface_details(source),
        },
    )


def _surface_details(source: SurfaceSource) -> dict[str, Any]:
    return {
        "table": source.table.label,
        "surface_method": source.method,
        "bounds_cover_deployed_surface": source.covers_deployed,
        "surface_error_bound": source.error_bound,
        "bounds_are": source.describe(),
    }


def loop_equilibrium(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    fuzzy: FuzzyPart | None,
) -> Equilibrium:
    """The loop's rest point for these gains, against the force-controlled set point."""
    if controller != "fuzzy-pi":
        return pi_equilibrium()
    if fuzzy is None:
        raise ConfigError("fuzzy-pi needs the rule base's bounds")
    all_gains, _, _ = effective_gains(controller, gains)
    return fuzzy_equilibrium(fuzzy.zeros, all_gains["ki"], _setpoint(exp))


def other_rest_point(fuzzy: FuzzyPart, ki: float) -> str:
    """Why another rest point may lie in the box the certificate covers ("" if none can).

    The box is ``|Ki*e| <= rho`` around the set point (the invariant level set lies inside
    it); ``fuzzy.rest`` proves where ``F(x, 0)`` cannot vanish.
    """
    proof = fuzzy.rest
    if isinstance(proof, str):
        return proof
    found = proof.within(-fuzzy.rho, fuzzy.rho)
    if not found:
        return ""
    a, b = found[0]
    return (
        f"F(Ki*e, 0) may vanish at Ki*e in [{a:.4g}, {b:.4g}] (e = {a / ki:.3g} to "
        f"{b / ki:.3g} N), inside the region the certificate covers (|Ki*e| <= {fuzzy.rho:.3g}):"
        " the loop can rest there, off the set point"
    )


def _setpoint(exp: Experiment) -> float:
    """The (first) force-controlled axis's set point, in N."""
    return float(next(exp.setpoints[i] for i in range(3) if exp.selection[i]))


@dataclass(frozen=True, slots=True)
class Cell:
    """One grid cell's verdict."""

    stiffness_n_per_mm: float
    latency: tuple[int, int]
    certified: bool
    margin: float
    solver_status: str
    stable: bool = False
    noise_std_n: float = math.nan
    contact_sector: tuple[float, float] | None = None
    #: the verified Lyapunov matrix (None when none was found); not part of the JSON
    lyapunov_p: FloatArray | None = field(default=None, repr=False, compare=False)
    #: why the cell is not certified ("" when it is)
    why_not: str = ""
    #: the largest force deviation (N) from the rest point for which the certificate holds
    #: (:mod:`fuzzkit.analysis.invariant_region`; NaN without a Lyapunov function)
    region_n: float = math.nan
    region_limited_by: str = ""
    #: the half-width of the box of scaled inputs |Ki (e - e0)|, |Kp de| the fuzzy bounds
    #: were taken on (NaN for PI)
    fuzzy_box: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """JSON form (a NaN or infinite number becomes null)."""
        return {
            "stiffness_n_per_mm": self.stiffness_n_per_mm,
            "latency_periods": list(self.latency),
            "certified": self.certified,
            "margin": _finite(self.margin),
            "lyapunov_certificate": self.stable,
            "noise_std_n": _finite(self.noise_std_n),
            "contact_sector": None if self.contact_sector is None else list(self.contact_sector),
            "solver_status": self.solver_status,
            "why_not_certified": self.why_not or None,
            "region_n": _finite(self.region_n),
            "region_limited_by": self.region_limited_by or None,
            "fuzzy_region_scaled": _finite(self.fuzzy_box),
        }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


@dataclass(frozen=True, slots=True)
class Region:
    """The verdict of every cell and the model they were judged on."""

    model: dict[str, Any]
    cells: tuple[Cell, ...]
    method: str = METHOD

    def as_dict(self) -> dict[str, Any]:
        """The JSON of ``fuzzkit stability --json``."""
        return {
            "method": self.method,
            "model": self.model,
            "cells": [c.as_dict() for c in self.cells],
        }


def effective_gains(
    controller: str, gains: Mapping[str, float] | None
) -> tuple[dict[str, float], float, float]:
    """The controller's gains (defaults updated by ``gains``) and the incremental law's
    ``(kp, ki)`` in m/N: PI's own, the fuzzy-PI's ``Kx*Kp`` and ``Kx*Ki``."""
    if controller not in CONTROLLERS:
        raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
    g = dict(DEFAULT_GAINS[controller])
    g.update(gains or {})
    if controller == "pi":
        return g, g["kp"], g["ki"]
    return g, g["kx"] * g["kp"], g["kx"] * g["ki"]


def axis_loop(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    inner: InnerLoop,
    fuzzy: FuzzyPart | None,
    stiffness_n_per_m: float,
    latency: tuple[int, int],
    sigma_min: float = SIGMA_MIN,
    frontend_cutoff_hz: float | None = None,
    gain_scale: tuple[float, float] = (1.0, 1.0),
) -> AxisLoop:
    """The linear model of a force axis of ``exp`` at one stiffness and latency
    (``frontend_cutoff_hz``: the controller's own low-pass, a spec's; ``gain_scale``: the
    interval of an adaptation's factor of the increment, ``0 < lo <= hi``, which multiplies
    ``phi``, and ``phi_de`` where given: the model is affine in each)."""
    _, kp, ki = effective_gains(controller, gains)
    scn = exp.scenario
    phi, phi_de = (1.0, 1.0), None
    if controller == "fuzzy-pi":
        if fuzzy is None:
            raise ConfigError("fuzzy-pi needs the rule base's bounds")
        phi, phi_de = fuzzy.phi, fuzzy.phi_de
    lo, hi = gain_scale
    if (lo, hi) != (1.0, 1.0):
        phi = (phi[0] * lo, phi[1] * hi)
        phi_de = None if phi_de is None else (phi_de[0] * lo, phi_de[1] * hi)
    first, *more = inner.at(stiffness_n_per_m)
    return AxisLoop(
        period_s=scn.period_s,
        stiffness_n_per_m=stiffness_n_per_m,
        damping_n_s_per_m=scn.contact.damping_n_s_per_m,
        sensor_delay=latency[0],
        command_delay=latency[1],
        filter_cutoff_hz=scn.sensor.cutoff_hz,
        kp=kp,
        ki=ki,
        phi=phi,
        phi_de=phi_de,
        inner_a=first.a,
        inner_g=first.g,
        inner_q=first.q,
        inner_b=first.b,
        inner_h=first.h,
        inner_more=tuple(more),
        contact_lag=inner.contact_lag,
        sigma_min=sigma_min,
        frontend_cutoff_hz=frontend_cutoff_hz,
    )


def certify_cell(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    inner: InnerLoop,
    fuzzy: FuzzyPart | None,
    stiffness_n_per_mm: float,
    latency: tuple[int, int],
    sigma_min: float,
    noise_n: float,
    reuse: FloatArray | None = None,
    *,
    frontend_cutoff_hz: float | None = None,
    limits_m: tuple[float, float] | None = None,
    gain_scale: tuple[float, float] = (1.0, 1.0),
) -> Cell:
    """Certify one cell on the fuzzy box of ``fuzzy`` (:func:`certify_box`); a fuzzy-PI cell
    refused there because a vertex (or a product of two) is unstable is tried on smaller boxes
    around the rest point (:func:`local_parts`): the largest whose vertices are all stable,
    then smaller ones, :data:`LOCAL_TRIES` searches at most. A box is certified with its own
    bounds and its own ``region_n``. A rule base with a possible second rest point in the
    first box is not tried again (the loop could rest there)."""
    args = (exp, controller, gains, inner)
    rest = (stiffness_n_per_mm, latency, sigma_min, noise_n, reuse)
    opts = {
        "frontend_cutoff_hz": frontend_cutoff_hz,
        "limits_m": limits_m,
        "gain_scale": gain_scale,
    }
    cell = certify_box(*args, fuzzy, *rest, **opts)  # type: ignore[arg-type]
    if cell.certified or fuzzy is None or cell.why_not.startswith(("the set point", "no rest")):
        return cell
    if not cell.solver_status.startswith("refused"):
        # the box's vertices were stable and no Lyapunov function was found for them: a
        # smaller box rarely changes that, and each try is a solve
        return cell
    tries = 0
    for part in local_parts(fuzzy):
        loop = axis_loop(
            exp,
            controller,
            gains,
            inner,
            part,
            stiffness_n_per_mm * 1e3,
            latency,
            1.0,
            frontend_cutoff_hz,
            gain_scale,
        )
        mats = vertex_matrices(loop)
        if max(float(np.max(np.abs(np.linalg.eigvals(a)))) for a in mats) >= 1.0:
            continue
        local = certify_box(*args, part, *rest, **opts)  # type: ignore[arg-type]
        if local.certified:
            return local
        tries += 1
        if tries >= LOCAL_TRIES:
            break
    return cell


def certify_box(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    inner: InnerLoop,
    fuzzy: FuzzyPart | None,
    stiffness_n_per_mm: float,
    latency: tuple[int, int],
    sigma_min: float,
    noise_n: float,
    reuse: FloatArray | None = None,
    *,
    frontend_cutoff_hz: float | None = None,
    limits_m: tuple[float, float] | None = None,
    gain_scale: tuple[float, float] = (1.0, 1.0),
) -> Cell:
    """Certify one cell on one fuzzy box: with the contact sector ``[sigma_min, 1]`` (contact
    may be lost), else with contact held (``[1, 1]``); ``Cell.contact_sector`` says which one holds.

    Contact held is tried first: its vertices are a subset of the wider sector's, so when it
    fails the wider one fails too and is not tried. ``reuse``: a Lyapunov matrix to try before
    any solve (a neighbouring cell's); it certifies only if it passes the numpy check on this
    cell's vertices. ``frontend_cutoff_hz``, ``limits_m``: a spec's low-pass and its
    ``(step_m, correction_m)`` limits (the region ``region_n`` keeps them from clipping).
    """
    rest = loop_equilibrium(exp, controller, gains, fuzzy)
    lat = (int(latency[0]), int(latency[1]))
    if fuzzy is not None and fuzzy.kind == "none":
        why = f"no rest point: {rest.why}"
        return Cell(float(stiffness_n_per_mm), lat, False, math.nan, "refused", why_not=why)
    loop = axis_loop(
        exp,
        controller,
        gains,
        inner,
        fuzzy,
        stiffness_n_per_mm * 1e3,
        latency,
        sigma_min,
        frontend_cutoff_hz,
        gain_scale,
    )
    held = replace(loop, sigma_min=1.0)
    cert = certify(vertex_matrices(held), vertex_matrices(held, nominal_plant=True), (reuse,))
    sector, certified_loop = (1.0, 1.0), held
    if cert.certified and sigma_min < 1.0:
        wide = certify(
            vertex_matrices(loop), vertex_matrices(loop, nominal_plant=True), (reuse, cert.p)
        )
        if wide.certified:
            cert, sector, certified_loop = wide, (sigma_min, 1.0), loop
    region_n, limited_by = math.nan, ""
    if cert.certified and cert.p is not None:
        box = None
        if fuzzy is not None:
            all_gains = effective_gains(controller, gains)[0]
            box = (fuzzy.rho, all_gains["ki"], all_gains["kp"])
        # the model is about the rest point: its contact force is the set point's plus the
        # rest point's offset (0 when they coincide)
        rest_force = _setpoint(exp) + rest.offset_n
        if rest_force > 0.0:
            found = level_set(cert.p, validity_slabs(certified_loop, rest_force, box, limits_m))
            region_n, limited_by = found.region_n, found.limited_by
        else:
            region_n, limited_by = 0.0, "no contact force at the rest point"
    noise = noise_std(loop, noise_n)
    quiet = noise <= NOISE_SHARE * BAND_N
    why = ""
    if not cert.certified:
        why = f"no common Lyapunov function ({cert.solver_status})"
    elif not quiet:
        why = f"the nominal model predicts {noise:.3g} N of noise, above {NOISE_SHARE * BAND_N:g} N"
    lone = True
    if not rest.at_setpoint:
        # the model is about the rest point; the set point is not it, so "settles at the set
        # point" cannot be certified, whatever the Lyapunov function says about the rest point
        stable = "stable" if cert.certified else "not proven stable"
        why = f"the set point is not the loop's rest point ({stable} around it): {rest.why}"
    elif fuzzy is not None:
        other = other_rest_point(fuzzy, effective_gains(controller, gains)[0]["ki"])
        if other:
            lone = False
            stable = "stable" if cert.certified else "not proven stable"
            why = f"the set point may not be the only rest point ({stable}): {other}"
    return Cell(
        float(stiffness_n_per_mm),
        lat,
        cert.certified and quiet and rest.at_setpoint and lone,
        cert.margin,
        cert.solver_status,
        cert.certified,
        noise,
        sector if cert.certified else None,
        cert.p if cert.certified else None,
        why,
        region_n,
        limited_by,
        math.nan if fuzzy is None else fuzzy.rho,
    )


def certify_cells(
    exp: Experiment,
    controller: str,
    gains: Mapping[str, float] | None,
    inner: InnerLoop,
    fuzzy: FuzzyPart | None,
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    sigma_min: float,
    noise_n: float,
    *,
    frontend_cutoff_hz: float | None = None,
    limits_m: tuple[float, float] | None = None,
    gain_scale: Callable[[float], tuple[float, float]] | None = None,
) -> Iterator[Cell]:
    """Every cell, stiffness by stiffness; each tries first the Lyapunov matrix that last
    certified the same latency (the same state size), re-verified on its own vertices.
    ``gain_scale``: an adaptation's factor interval at each stiffness (N/mm)."""
    last: dict[tuple[int, int], FloatArray | None] = {}
    for k in stiffnesses_n_per_mm:
        for lat in latencies:
            cell = certify_cell(
                exp,
                controller,
                gains,
                inner,
                fuzzy,
                k,
                lat,
                sigma_min,
                noise_n,
                last.get(lat),
                frontend_cutoff_hz=frontend_cutoff_hz,
                limits_m=limits_m,
                gain_scale=(1.0, 1.0) if gain_scale is None else gain_scale(k),
            )
            if cell.lyapunov_p is not None:
                last[lat] = cell.lyapunov_p
            yield cell


def certify_region(
    exp: Experiment,
    controller: str,
    plant: str,
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    *,
    gains: Mapping[str, float] | None = None,
    rulebase: str | RuleBase = "macvicar_whelan",
    fuzzy_region: float = 1.0,
    sigma_min: float = SIGMA_MIN,
    surface: Surface = EXACT,
    frontend_cutoff_hz: float | None = None,
    limits_m: tuple[float, float] | None = None,
    deployed: dict[str, Any] | None = None,
    gain_scale: Callable[[float], tuple[float, float]] | None = None,
) -> Region:
    """Certify every (stiffness, latency) cell for ``controller`` on ``plant``'s inner loop.

    ``surface``: how the fuzzy-PI evaluates ``rulebase`` (inputs in role order).
    ``frontend_cutoff_hz``, ``limits_m``: a spec's low-pass and ``(step_m, correction_m)``.
    ``deployed``: what the certified controller is (a spec's name and file, or the defaults
    assumed), for the JSON. ``gain_scale``: an adaptation's factor of the increment, the
    interval it may take at each stiffness (N/mm); the factor may switch within it from one
    period to the next (:mod:`fuzzkit.analysis.schedule_certificate`).
    """
    all_gains, kp, ki = effective_gains(controller, gains)
    inner = identify(plant)
    fuzzy = fuzzy_part(rulebase, fuzzy_region, surface) if controller == "fuzzy-pi" else None
    noise_n = exp.scenario.sensor.noise_std_n
    cells = certify_cells(
        exp,
        controller,
        gains,
        inner,
        fuzzy,
        stiffnesses_n_per_mm,
        latencies,
        sigma_min,
        noise_n,
        frontend_cutoff_hz=frontend_cutoff_hz,
        limits_m=limits_m,
        gain_scale=gain_scale,
    )
    setpoints = [exp.setpoints[i] for i in range(3) if exp.selection[i]]
    rest = loop_equilibrium(exp, controller, gains, fuzzy)
    model: dict[str, Any] = {
        "scenario": exp.name,
        "controller": controller,
        "gains": all_gains,
        "incremental_gains_m_per_n": {"kp": kp, "ki": ki},
        "plant": plant,
        "period_s": exp.scenario.period_s,
        "contact_damping_n_s_per_m": exp.scenario.contact.damping_n_s_per_m,
        "deployed": deployed or {},
        "sensor_filter_cutoff_hz": exp.scenario.sensor.cutoff_hz,
        "frontend_lowpass_hz": frontend_cutoff_hz,
        "limits_m": None
        if limits_m is None
        else {"step_m": limits_m[0], "correction_m": limits_m[1]},
        "contact_sector": [sigma_min, 1.0],
        "contact_sector_fallback": [1.0, 1.0],
        "contact_sector_holds_while_force_above_n": [
            (1.0 - 1.0 / sigma_min) * sp for sp in setpoints
        ],
        "equilibrium": rest.as_dict(),
        "inner_loop": inner.as_dict(),
        "sensor_noise_std_n": noise_n,
        "certified_means": (
            "the Lyapunov certificate holds and the nominal model predicts a noise-driven "
            f"force standard deviation <= {NOISE_SHARE * BAND_N:g} N"
        ),
        "not_covered": ["impact", "friction", "joint saturation"]
        + ([] if limits_m else ["correction and rate limits"]),
    }
    if fuzzy is not None:
        model["fuzzy"] = {
            "rulebase": rulebase if isinstance(rulebase, str) else rulebase.name,
            "bounds": fuzzy.kind,
            "zero_set_scaled_error": [list(iv) for iv in fuzzy.zeros.intervals],
            "lone_rest_point": fuzzy.rest
            if isinstance(fuzzy.rest, str)
            else {
                **fuzzy.rest.as_dict(),
                "unresolved_near_set_point_n": [v / all_gains["ki"] for v in fuzzy.rest.near],
            },
            "region": {
                "abs_ki_e_max": fuzzy.rho,
                "abs_kp_de_max": fuzzy.rho,
                "abs_e_max_n": fuzzy.rho / all_gains["ki"],
                "abs_de_max_n_per_period": fuzzy.rho / all_gains["kp"],
            },
            **fuzzy.details,
        }
    return Region(model, tuple(cells))


@dataclass(frozen=True, slots=True)
class CertifiedOver:
    """A gain-set predicate: certified in every cell of a stiffness x latency grid
    (``fuzzkit tune --certify``). Stops at the first cell that is not."""

    experiment: Experiment
    controller: str
    plant: str
    stiffnesses_n_per_mm: tuple[float, ...]
    latencies: tuple[tuple[int, int], ...]
    rulebase: str = "macvicar_whelan"
    sigma_min: float = SIGMA_MIN

    def __call__(self, gains: Mapping[str, float]) -> bool:
        inner = identify(self.plant)
        fuzzy = fuzzy_part(self.rulebase) if self.controller == "fuzzy-pi" else None
        noise_n = self.experiment.scenario.sensor.noise_std_n
        cells = certify_cells(
            self.experiment,
            self.controller,
            gains,
            inner,
            fuzzy,
            self.stiffnesses_n_per_mm,
            self.latencies,
            self.sigma_min,
            noise_n,
        )
        return all(cell.certified for cell in cells)
