"""Online adaptation of the output scaling factor: the reference arithmetic.

What :mod:`fuzzkit.control.adaptation_spec` describes, per force-controlled axis, one period at
a time. The generated controllers (``codegen/backends/*/controller.*.jinja``) repeat these
operations in the same order; ``docs/controller.md`` ("Adaptation") is the contract.

* :class:`StiffnessSchedule`: the stiffness estimate (recursive least squares with forgetting,
  in its sufficient-statistics form ``S_uu = lambda*S_uu + du^2``, ``S_uf = lambda*S_uf +
  du*df``, ``k = clip(S_uf / S_uu, k_min, k_max)``, which is exactly the RLS estimate of
  ``df = k*du`` with a zero-weight prior) over windowed increments, gated by excitation, and
  the band it selects, changed at most once per dwell time.
* :func:`alpha`: the self-tuning gain after Mudi and Pal (1999) from the 7x7 rule base
  :data:`ALPHA_RULES` on the normalised ``E``, ``dE``.

Both return the factor ``s`` the axis controller multiplies its increment by: ``du = s *
du_fixed`` (``du_fixed = kx*F(...)`` or ``kp*de + ki*e``). The incremental form makes a change
of ``s`` bumpless: ``u_k = u_{k-1} + du_k`` is continuous whatever ``s`` does.
"""

from __future__ import annotations

import math

from fuzzkit.control import status as st
from fuzzkit.control.adaptation_spec import Adaptation

#: The least spread of the window increments ``du`` the slope needs: the normalised determinant
#: ``(S_uu*S_1 - S_u^2) / (S_uu*S_1)`` (0: all equal, 1: symmetric about 0) must exceed it.
SPREAD = 0.05
#: A period whose own ratio ``df/du`` exceeds ``JUMP`` times the estimate, with ``|df|`` at least
#: ``JUMP`` times the excitation threshold, is a sudden stiffening: the estimate restarts from
#: that ratio and the least squares from nothing (the gain can only drop by it).
JUMP = 4.0
#: The estimate moves only in contact: both ends of the window must hold a force of at least
#: ``CONTACT`` times the excitation threshold ``min_force_n`` (1 N with the kit's default 0.2 N,
#: the experiments' engage threshold). Out of contact the force is noise alone and its increments
#: over the corrections' would pull the estimate to ``k_min``: it is frozen instead.
CONTACT = 5.0
#: The estimate is trusted after this many least-squares updates since the schedule started or
#: restarted on a sudden stiffening; until then the schedule runs its band of ``k_max``
#: (:meth:`~fuzzkit.control.adaptation_spec.Adaptation.safe_band`), whatever the estimate.
#: The count needs no excitation from the gain itself beyond what that band makes: each
#: update needs only ``|du| >= min_step_m`` and ``|df| >= min_force_n`` over a window.
TRUST_UPDATES = 4
#: Or the estimate is trusted once the secant since the first contact period (after a start or
#: a restart) spans ``TRUST_SPAN`` times both excitation thresholds: ``|m - m_0| >= TRUST_SPAN *
#: min_step_m`` and ``|f - f_0| >= TRUST_SPAN * min_force_n``; the estimate is then that secant.
#: However small the safe band's gain, its integrator keeps moving the correction while the
#: force is off the set point, so the secant's span grows until it counts: the trust does not
#: wait for the windowed excitation a low gain may never make (a soft contact under the band
#: of k_max). Its error is the force noise over ``TRUST_SPAN * min_force_n``.
TRUST_SPAN = 2.0

#: Singleton values of alpha's labels ZE, VS, S, SB, M, B, VB on [0, 1].
ALPHA_LEVELS = {"ZE": 0.0, "VS": 1.0 / 6.0, "S": 2.0 / 6.0, "SB": 3.0 / 6.0, "M": 4.0 / 6.0,
                "B": 5.0 / 6.0, "VB": 1.0}  # fmt: skip
#: alpha's rule base: rows E = NL .. PL, columns dE = NL .. PL (7 triangular labels on [-1, 1]).
#: Large when the error is large and growing (e and de of one sign), small near the set point
#: and when the error is already shrinking fast (the rule Mudi and Pal state in words: more gain
#: to leave a large error, less to avoid overshoot while approaching). The kit's own entries:
#: not compared with the paper's table.
ALPHA_RULES = (
    ("VB", "VB", "VB", "B", "SB", "S", "ZE"),
    ("VB", "VB", "B", "B", "M", "S", "VS"),
    ("VB", "M", "B", "VB", "VS", "S", "VS"),
    ("S", "SB", "M", "ZE", "M", "SB", "S"),
    ("VS", "S", "VS", "VB", "B", "M", "VB"),
    ("VS", "S", "M", "B", "B", "VB", "VB"),
    ("ZE", "S", "SB", "B", "VB", "VB", "VB"),
)
#: The rule table as numbers, ``ALPHA_TABLE[i][j]`` for E label i and dE label j.
ALPHA_TABLE = tuple(tuple(ALPHA_LEVELS[c] for c in row) for row in ALPHA_RULES)


def _label(x: float) -> tuple[int, float]:
    """The lower of the two 7-label triangles ``x`` (in [-1, 1]) lies between, and the
    membership ``t`` of the upper one (the lower has ``1 - t``)."""
    p = (x + 1.0) * 3.0
    i = min(int(p), 5)
    return i, p - i


def alpha(e_norm: float, de_norm: float) -> float:
    """The rule base's alpha in [0, 1] at the normalised (clipped) ``E``, ``dE``.

    Min for AND; the crisp alpha is the weighted mean of the fired rules' singletons (the
    paper's eq. 10); at most four rules fire on the uniform triangular partition.
    """
    i, t = _label(e_norm)
    j, s = _label(de_norm)
    w00 = min(1.0 - t, 1.0 - s)
    w01 = min(1.0 - t, s)
    w10 = min(t, 1.0 - s)
    w11 = min(t, s)
    num = (
        w00 * ALPHA_TABLE[i][j]
        + w01 * ALPHA_TABLE[i][j + 1]
        + w10 * ALPHA_TABLE[i + 1][j]
        + w11 * ALPHA_TABLE[i + 1][j + 1]
    )
    return num / (w00 + w01 + w10 + w11)


class SelfTuning:
    """The self-tuning factor of one axis: ``s = alpha_min + (alpha_max - alpha_min) *
    alpha(clip(ge*e), clip(gde*de))`` with the input gains ``ge``, ``gde`` (1/N)."""

    def __init__(self, ad: Adaptation, ge: float, gde: float) -> None:
        self.low, self.span = ad.alpha_min, ad.alpha_max - ad.alpha_min
        self.ge, self.gde = ge, gde
        self.last = 1.0

    def __call__(self, e: float, de: float) -> float:
        en = min(max(self.ge * e, -1.0), 1.0)
        den = min(max(self.gde * de, -1.0), 1.0)
        self.last = self.low + self.span * alpha(en, den)
        return self.last

    def reset(self) -> None:
        """Nothing is remembered between periods but the last factor (for recordings)."""
        self.last = 1.0


class StiffnessSchedule:
    """The stiffness estimate of one axis and the band it schedules.

    :meth:`observe` once per engaged, untripped period, before the axis controller steps, with
    the force the axis controller sees (NaN when the sample is held: missing, rejected, taring)
    and the correction ``u`` before this period's step.
    """

    def __init__(self, ad: Adaptation, period_s: float) -> None:
        self.ad = ad
        est = ad.estimator
        self.window = est.window_periods
        self.delay = est.delay_periods
        self.size = est.window_periods + est.delay_periods
        self.dwell = ad.dwell_periods(period_s)
        self.reset()

    def reset(self) -> None:
        """No history, the initial estimate, its band; a band change is allowed at once."""
        est = self.ad.estimator
        self.f_hist = [math.nan] * self.size
        self.u_hist = [0.0] * self.size
        self.pos = 0  # where this period is written in the ring (periods observed, mod size)
        self.s_uu = 0.0
        self.s_u = 0.0
        self.s_1 = 0.0
        self.s_uf = 0.0
        self.s_f = 0.0
        self.x = 0.0  # the inner-loop model's states (Estimator: inner_q, inner_a, inner_g)
        self.m = 0.0
        self.k = est.initial_n_mm
        self.updates = 0
        self.jumps = 0
        self.fresh = 0  # updates since the start or the last sudden stiffening
        self.beyond = False  # the last reading was stiffer than k_max
        self.f0 = math.nan  # the secant's first contact period: force and tool motion
        self.m0 = 0.0
        self.band = self.ad.safe_band()
        self.since = self.dwell

    @property
    def trusted(self) -> bool:
        """The estimate has had :data:`TRUST_UPDATES` updates since the last (re)start."""
        return self.fresh >= TRUST_UPDATES

    @property
    def status(self) -> int:
        """The schedule's status bits (``UNTRUSTED``, ``OUT_OF_RANGE``)."""
        return (0 if self.trusted else st.UNTRUSTED) | (st.OUT_OF_RANGE if self.beyond else 0)

    @property
    def scale(self) -> float:
        """The output-gain factor: the current band's, or the 1/k schedule's at the estimate
        (at ``k_max`` until the estimate is trusted and beyond ``k_max``)."""
        if self.ad.inverse_n_mm is not None:
            est = self.ad.estimator
            used = self.k if self.trusted and not self.beyond else est.k_max_n_mm
            return self.ad.inverse_factor(used)
        return self.ad.bands[self.band].scale

    @property
    def last(self) -> float:
        """The factor of the last step (the current band's)."""
        return self.scale

    def __call__(self, e: float, de: float) -> float:
        """The axis controller's factor this period: the current band's (e, de unused)."""
        return self.scale

    def observe(self, f: float, u: float) -> None:
        """One period: record ``(f_k, m_{k-1})`` (``m``: the inner-loop model's response to the
        corrections up to ``u_{k-1}``), update the estimate when the window is excited, then
        move to the estimate's band: at once when that lowers the gain, after the dwell time
        since the last change when it raises it."""
        est = self.ad.estimator
        n = self.size
        p = self.pos
        self.x = est.inner_q * self.x + (1.0 - est.inner_q) * u
        self.m = est.inner_a * self.m + (1.0 - est.inner_a) * est.inner_g * self.x
        self.f_hist[p] = f
        self.u_hist[p] = self.m
        self.pos = (p + 1) % n
        # f_{k-W}; u_{k-D} is stored with period k-D+1, u_{k-D-W} with period k-D-W+1 = k-n+1
        df = f - self.f_hist[(p + n - self.window) % n]
        du = self.u_hist[(p + n + 1 - self.delay) % n] - self.u_hist[(p + 1) % n]
        # the same over one period, for a sudden stiffening (an oscillation's increments
        # cancel over a window, not over a period)
        df1 = f - self.f_hist[(p + n - 1) % n]
        du1 = self.u_hist[(p + n + 1 - self.delay) % n] - self.u_hist[(p + n - self.delay) % n]
        if math.isfinite(df1) and abs(du1) >= est.min_step_m and abs(df1) >= JUMP * est.min_force_n:
            du1_mm = 1000.0 * du1
            bound = JUMP * self.k * du1_mm
            if df1 > bound if du1_mm > 0.0 else df1 < bound:
                # a harder layer: the past says nothing about it, start afresh from here
                ratio = df1 / du1_mm
                self.beyond = ratio > est.k_max_n_mm
                self.k = min(max(ratio, est.k_min_n_mm), est.k_max_n_mm)
                self.s_uu = self.s_u = self.s_1 = self.s_uf = self.s_f = 0.0
                self.jumps += 1
                self.fresh = 0
                self.f0 = math.nan
                df = math.nan  # this period is used up
        contact = CONTACT * est.min_force_n
        touching = abs(f) >= contact and abs(self.f_hist[(p + n - self.window) % n]) >= contact
        if not self.trusted:
            self._secant(f, self.u_hist[(p + n + 1 - self.delay) % n], contact)
        excited = abs(du) >= est.min_step_m and abs(df) >= est.min_force_n
        if math.isfinite(df) and touching and excited:
            du_mm = 1000.0 * du
            lam = est.forgetting
            self.s_uu = lam * self.s_uu + du_mm * du_mm
            self.s_u = lam * self.s_u + du_mm
            self.s_1 = lam * self.s_1 + 1.0
            self.s_uf = lam * self.s_uf + du_mm * df
            self.s_f = lam * self.s_f + df
            det = self.s_uu * self.s_1 - self.s_u * self.s_u
            if det > SPREAD * self.s_uu * self.s_1:
                slope = (self.s_1 * self.s_uf - self.s_u * self.s_f) / det
                self.beyond = slope > est.k_max_n_mm
                self.k = min(max(slope, est.k_min_n_mm), est.k_max_n_mm)
                self.updates += 1
                self.fresh = min(self.fresh + 1, TRUST_UPDATES)
        if self.ad.inverse_n_mm is not None:
            return  # the 1/k schedule has no bands: its factor follows the estimate
        if self.since < self.dwell:
            self.since += 1
        if self.beyond:
            target = self.ad.floor_band()
        elif self.trusted:
            target = self.ad.band_of(self.k)
        else:
            target = self.ad.safe_band()
        scales = self.ad.bands
        lower = scales[target].scale < scales[self.band].scale
        if target != self.band and (lower or self.since >= self.dwell):
            self.band = target
            self.since = 0

    def _secant(self, f: float, m: float, contact: float) -> None:
        """The untrusted estimate's secant since its first contact period: ``f`` this period's
        force (NaN: held), ``m`` the tool motion it answers (``m_{k-D}``)."""
        if not (math.isfinite(f) and abs(f) >= contact):
            self.f0 = math.nan  # out of contact (or held): the secant starts again
            return
        if math.isnan(self.f0):
            self.f0, self.m0 = f, m
            return
        est = self.ad.estimator
        dm, df = m - self.m0, f - self.f0
        if abs(dm) >= TRUST_SPAN * est.min_step_m and abs(df) >= TRUST_SPAN * est.min_force_n:
            slope = df / (1000.0 * dm)
            if slope > 0.0:
                self.beyond = slope > est.k_max_n_mm
                self.k = min(max(slope, est.k_min_n_mm), est.k_max_n_mm)
                self.fresh = TRUST_UPDATES
