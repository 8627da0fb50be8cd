"""The force loop of one task axis, in contact, around its set point, as a linear system with
bounded time-varying gains (docs/stability.md states and justifies it).

Per controller period ``T``, in deviations from the equilibrium (force at the set point), with
every state in newtons (positions and corrections times the contact stiffness ``k``):

* inner motion loop: two lags, ``x[k+1] = q x[k] + (1 - q) r[k+1]``,
  ``p[k+1] = a p[k] + (1 - a) g x[k+1]`` (identified, :mod:`fuzzkit.analysis.inner_loop`;
  ``a``, ``q``, ``g`` uncertain in intervals); on a plant with a slow mode (MuJoCo's
  friction creep behind the servo's overshoot), the fast lag has its own gain ``h`` and a slow
  lag ``y[k+1] = b y[k] + (1 - b) (g - h) x[k+1]`` brings the position ``p + y`` to ``g``;
* contact: ``f[k+1] = sigma * (k ((1 - l) p[k+1] + l p[k]) + c (p[k+1] - p[k]) / T)``;
  ``sigma`` in ``[sigma_min, 1]`` is the sector of the clamp ``max(0, .)`` that lets the tool
  leave the surface (loss of contact); ``l`` in ``contact_lag`` is the fraction of a period by
  which the force the sensor sample stands for precedes the period's end (arm6: 0, contact and
  sensor are evaluated once, at the period's end; planar arm: its sensor filters the forces of
  4 physics substeps, each evaluated at the substep's start, :func:`substep_lag`);
* F/T sensor: first-order filter sampled once per period, ``w[k+1] = beta w[k] + (1 - beta)
  f[k+1]``, ``beta = exp(-2 pi f_c T)``;
* sensor delay ``S`` periods: the controller sees ``y[k] = w[k - S]``;
* controller: ``u[k] = u[k-1] + phi (Kp (e[k] - e[k-1]) + Ki e[k])``, ``e = -y``; PI:
  ``phi = 1``; fuzzy-PI: ``Kp = Kx*Kp_fuzzy``, ``Ki = Kx*Ki_fuzzy`` and ``phi`` in the bounds of
  :mod:`fuzzkit.analysis.fuzzy_bounds`;
* command delay ``C`` periods plus the one period every correction waits for the next plant
  step: ``r[k+1] = u[k - C]``.

The state is ``(p[k], x[k], [y[k],] w[k], ..., w[k-S], u[k], ..., u[k-C])``, of size
``S + C + 4`` (one more with the slow lag, one more with a front-end low-pass).
The closed-loop matrix is multi-affine in ``(sigma, phi, a, q, g, b, h)`` (no parameter
appears squared), so for any values in the box it is a convex combination of its values at the box's
vertices
(:func:`vertex_matrices`): a Lyapunov function common to the vertices holds for every
combination, varying from one period to the next.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class InnerBox:
    """One box of the inner loop's parameters: intervals of ``a``, ``g``, ``q`` and, with the
    slow lag, ``b`` and ``h``."""

    a: tuple[float, float]
    g: tuple[float, float]
    q: tuple[float, float]
    b: tuple[float, float] | None = None
    h: tuple[float, float] | None = None


@dataclass(frozen=True, slots=True)
class AxisLoop:
    """Everything the linear model of one force axis needs (SI units).

    ``kp``, ``ki``: the incremental law's gains in m/N (the fuzzy-PI's ``Kx*Kp``, ``Kx*Ki``);
    ``phi``: the interval multiplying both (``(1, 1)`` for PI); ``phi_de``: when given, the
    ``kp`` term has its own interval and ``phi`` multiplies the ``ki`` term only (the gradient
    bounds of a surface without the PI-like structure). ``inner_a``, ``inner_g``: the inner
    loop's pole and gain intervals. ``sigma_min``: the lower end of the contact sector.
    """

    period_s: float
    stiffness_n_per_m: float
    damping_n_s_per_m: float
    sensor_delay: int
    command_delay: int
    filter_cutoff_hz: float
    kp: float
    ki: float
    phi: tuple[float, float] = (1.0, 1.0)
    phi_de: tuple[float, float] | None = None
    inner_a: tuple[float, float] = (0.0, 0.0)
    inner_g: tuple[float, float] = (1.0, 1.0)
    sigma_min: float = 0.1
    inner_q: tuple[float, float] = (0.0, 0.0)
    contact_lag: tuple[float, float] = (0.0, 0.0)
    #: the controller's own front-end low-pass (a spec's ``sensor.lowpass_hz``), after the
    #: sensor's filter and delay; None: the controller reads the sample as it is
    frontend_cutoff_hz: float | None = None
    #: the inner loop's slow lag: its pole ``b`` and the fast lag's own gain ``h`` (None: no
    #: slow lag, the fast lag has the whole gain ``g``)
    inner_b: tuple[float, float] | None = None
    inner_h: tuple[float, float] | None = None
    #: further boxes of the inner loop's parameters: the vertices are every box's (a cell
    #: between two identification stiffnesses: each neighbour's model with its uncertainty)
    inner_more: tuple[InnerBox, ...] = ()

    def __post_init__(self) -> None:
        problems = []
        for name in ("period_s", "stiffness_n_per_m", "filter_cutoff_hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                problems.append(f"{name} must be > 0 (got {v})")
        if not (math.isfinite(self.damping_n_s_per_m) and self.damping_n_s_per_m >= 0.0):
            problems.append(f"damping must be >= 0 (got {self.damping_n_s_per_m})")
        if self.sensor_delay < 0 or self.command_delay < 0:
            problems.append("delays must be whole periods >= 0")
        if any((b.b is None) != (self.inner_b is None) for b in self.inner_more) or (
            (self.inner_b is None) != (self.inner_h is None)
        ):
            problems.append("inner_b and inner_h go together, in every box")
        names = ("phi", "phi_de", "inner_a", "inner_g", "inner_q", "contact_lag", "inner_b")
        for name in (*names, "inner_h"):
            if getattr(self, name) is None:
                continue
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                problems.append(f"{name} must be an interval lo <= hi (got {lo}, {hi})")
        fc = self.frontend_cutoff_hz
        if fc is not None and not (math.isfinite(fc) and fc > 0.0):
            problems.append(f"frontend_cutoff_hz must be > 0 (got {fc})")
        if not 0.0 < self.sigma_min <= 1.0:
            problems.append(f"sigma_min must be in (0, 1] (got {self.sigma_min})")
        if problems:
            raise ConfigError("; ".join(problems))

    @property
    def slow(self) -> bool:
        """Whether the inner loop has its slow lag (state ``y``, after ``x``)."""
        return self.inner_b is not None

    @property
    def order(self) -> int:
        """The number of states (the front-end filter's, when there is one, is the last)."""
        extra = int(self.slow) + int(self.frontend_cutoff_hz is not None)
        return self.sensor_delay + self.command_delay + 4 + extra

    def layout(self) -> tuple[int, int, int, int]:
        """Indices of ``p``, ``x``, the first of the ``w`` queue and the first of the ``u``
        queue in the state (the slow lag ``y``, when there is one, sits at 2)."""
        iw = 2 + int(self.slow)
        return 0, 1, iw, iw + 1 + self.sensor_delay

    @property
    def frontend_pole(self) -> float:
        """The front-end low-pass's pole per period (0: no filter)."""
        if self.frontend_cutoff_hz is None:
            return 0.0
        return math.exp(-2.0 * math.pi * self.frontend_cutoff_hz * self.period_s)

    @property
    def filter_pole(self) -> float:
        """``beta``: the sensor filter's pole per period."""
        return math.exp(-2.0 * math.pi * self.filter_cutoff_hz * self.period_s)

    def as_dict(self) -> dict[str, object]:
        """JSON form."""
        out: dict[str, object] = asdict(self)
        out["filter_pole"] = self.filter_pole
        out["states"] = self.order
        return out


@dataclass(frozen=True, slots=True)
class StepRows:
    """Signals of one period as rows ``h`` (the signal is ``h @ x[k]``), in N.

    ``spring_next``: the contact force deviation the spring and damper give at the next plant
    step, before the clamp ``max(0, .)`` (the sector's argument). ``y_next``, ``y_now``: the
    samples the controller reads for ``e[k+1] = -y_next`` and ``de[k+1] = -(y_next - y_now)``.
    ``u_next``: the correction after the step. ``c_next``, ``c_now``: what the controller's
    law reads, the samples or, with a front-end low-pass, its output:
    ``e[k+1] = -c_next``, ``de[k+1] = -(c_next - c_now)``.
    """

    p_next: FloatArray
    x_next: FloatArray
    spring_next: FloatArray
    w_next: FloatArray
    y_next: FloatArray
    y_now: FloatArray
    u_now: FloatArray
    u_next: FloatArray
    c_next: FloatArray
    c_now: FloatArray
    #: the slow lag's next state (zeros without one)
    slow_next: FloatArray


def step_rows(
    loop: AxisLoop,
    sigma: float,
    phi: float,
    a: float,
    g: float,
    phi_de: float | None = None,
    q: float = 0.0,
    lag: float = 0.0,
    b: float = 0.0,
    h: float | None = None,
) -> StepRows:
    """The signals of one period for fixed values of the uncertain parameters (``b``, ``h``:
    the slow lag's pole and the fast lag's gain, read only when the loop has the slow lag)."""
    s, c = loop.sensor_delay, loop.command_delay
    n = loop.order
    k = loop.stiffness_n_per_m
    damp = loop.damping_n_s_per_m / (k * loop.period_s)
    beta = loop.filter_pole
    ip, ix, iw, iu = loop.layout()  # p, x, first of the w queue, first of the u queue

    def unit(i: int) -> FloatArray:
        e = np.zeros(n)
        e[i] = 1.0
        return e

    x_next = q * unit(ix) + (1.0 - q) * unit(iu + c)
    slow_next = np.zeros(n)
    pos_now = unit(ip)
    if loop.slow:
        fast = g if h is None else h
        p_next = a * unit(ip) + (1.0 - a) * fast * x_next
        slow_next = b * unit(ip + 2) + (1.0 - b) * (g - fast) * x_next
        pos_now = unit(ip) + unit(ip + 2)
    else:
        p_next = a * unit(ip) + (1.0 - a) * g * x_next
    # the tool's position: the fast lag's plus the slow lag's
    spring_next = (1.0 - lag + damp) * (p_next + slow_next) + (lag - damp) * pos_now
    w_next = beta * unit(iw) + (1.0 - beta) * sigma * spring_next
    y_next_sample = w_next if s == 0 else unit(iw + s - 1)
    y_now = unit(iw + s)
    c_next, c_now = y_next_sample, y_now
    if loop.frontend_cutoff_hz is not None:
        b2 = loop.frontend_pole
        c_now = unit(n - 1)
        c_next = b2 * c_now + (1.0 - b2) * y_next_sample
    kp, ki = loop.kp * k, loop.ki * k  # per newton of force deviation, in newtons of correction
    pd = phi if phi_de is None else phi_de
    u_next = unit(iu) - (pd * kp + phi * ki) * c_next + pd * kp * c_now
    return StepRows(
        p_next,
        x_next,
        spring_next,
        w_next,
        y_next_sample,
        y_now,
        unit(iu),
        u_next,
        c_next,
        c_now,
        slow_next,
    )


def closed_loop_matrix(
    loop: AxisLoop,
    sigma: float,
    phi: float,
    a: float,
    g: float,
    phi_de: float | None = None,
    q: float = 0.0,
    lag: float = 0.0,
    b: float = 0.0,
    h: float | None = None,
) -> FloatArray:
    """``A`` with ``x[k+1] = A x[k]`` for fixed values of the uncertain parameters
    (``phi_de`` None: the same ``phi`` on both terms)."""
    s, c = loop.sensor_delay, loop.command_delay
    n = loop.order
    ip, ix, iw, iu = loop.layout()  # p, x, first of the w queue, first of the u queue
    a_mat = np.zeros((n, n))

    def unit(i: int) -> FloatArray:
        e = np.zeros(n)
        e[i] = 1.0
        return e

    rows = step_rows(loop, sigma, phi, a, g, phi_de, q, lag, b, h)
    p_next, x_next, w_next, u_next = rows.p_next, rows.x_next, rows.w_next, rows.u_next
    a_mat[ip] = p_next
    a_mat[ix] = x_next
    if loop.slow:
        a_mat[ip + 2] = rows.slow_next
    a_mat[iw] = w_next
    for i in range(1, s + 1):
        a_mat[iw + i] = unit(iw + i - 1)
    a_mat[iu] = u_next
    for i in range(1, c + 1):
        a_mat[iu + i] = unit(iu + i - 1)
    if loop.frontend_cutoff_hz is not None:
        a_mat[n - 1] = rows.c_next
    return a_mat


def vertex_matrices(loop: AxisLoop, nominal_plant: bool = False) -> list[FloatArray]:
    """``A`` at every vertex of the parameter box (duplicates of degenerate intervals dropped).

    ``nominal_plant``: the inner loop's identified parameters (``a``, ``g``, ``q``, intervals
    as narrow as the fit error) at their mid-points, the others at their vertices: a smaller
    set to search a Lyapunov function on, before checking it on all.
    """
    return [closed_loop_matrix(loop, *v) for v in vertices(loop, nominal_plant)]


def vertex_rows(loop: AxisLoop) -> list[StepRows]:
    """:func:`step_rows` at every vertex of the parameter box."""
    return [step_rows(loop, *v) for v in vertices(loop)]


Vertex = tuple[float, float, float, float, float | None, float, float, float, float | None]


def vertices(loop: AxisLoop, nominal_plant: bool = False) -> list[Vertex]:
    """``(sigma, phi, a, g, phi_de, q, lag, b, h)`` at every vertex of the parameter box
    (``b`` 0 and ``h`` None without the slow lag)."""

    def corners(iv: tuple[float, float]) -> list[float]:
        return [0.5 * (iv[0] + iv[1])] if nominal_plant else sorted(set(iv))

    des: list[float | None] = [None]
    if loop.phi_de is not None:
        des = [*sorted(set(loop.phi_de))]
    first = InnerBox(loop.inner_a, loop.inner_g, loop.inner_q, loop.inner_b, loop.inner_h)
    out: list[Vertex] = []
    for box in (first, *loop.inner_more):
        bs: list[float] = [0.0]
        hs: list[float | None] = [None]
        if box.b is not None and box.h is not None:
            bs, hs = corners(box.b), [*corners(box.h)]
        out += itertools.product(
            sorted({loop.sigma_min, 1.0}),
            sorted(set(loop.phi)),
            corners(box.a),
            corners(box.g),
            des,
            corners(box.q),
            sorted(set(loop.contact_lag)),  # wide (planar): its corners stay in the core
            bs,
            hs,
        )
    return out


def noise_std(loop: AxisLoop, noise_std_n: float) -> float:
    """The force's standard deviation (N) that white sensor noise of ``noise_std_n`` causes in
    the nominal loop (contact held, ``phi`` and the inner loop at their interval mid-points).

    The noise enters the sample the controller reads (the sensor adds it after its filter), so
    the state is augmented by the last sample's noise; the stationary covariance solves a
    discrete Lyapunov equation. Infinite when the nominal loop is unstable.
    """
    from scipy.linalg import solve_discrete_lyapunov

    mid = [0.5 * (lo + hi) for lo, hi in (loop.phi, loop.inner_a, loop.inner_g, loop.inner_q)]
    phi_de = None if loop.phi_de is None else 0.5 * sum(loop.phi_de)
    lag = 0.5 * sum(loop.contact_lag)
    slow_b = 0.0 if loop.inner_b is None else 0.5 * sum(loop.inner_b)
    slow_h = None if loop.inner_h is None else 0.5 * sum(loop.inner_h)
    nominal = (1.0, mid[0], mid[1], mid[2], phi_de, mid[3], lag, slow_b, slow_h)
    a_mat = closed_loop_matrix(loop, *nominal)
    if max(abs(np.linalg.eigvals(a_mat))) >= 1.0:
        return math.inf
    n = loop.order
    k = loop.stiffness_n_per_m
    pd = mid[0] if phi_de is None else phi_de
    iu = loop.layout()[3]
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = a_mat
    b = np.zeros(n + 1)
    if loop.frontend_cutoff_hz is None:
        aug[iu, n] = pd * loop.kp * k  # + phi Kp n[k]: the previous sample's noise
        b[iu] = -(pd * loop.kp + mid[0] * loop.ki) * k  # - phi (Kp + Ki) n[k+1]
        b[n] = 1.0
    else:
        # the noise enters the front-end filter, whose state keeps the past noise
        gain = 1.0 - loop.frontend_pole
        b[n - 1] = gain
        b[iu] = -(pd * loop.kp + mid[0] * loop.ki) * k * gain
    # u[k+1] reads the new noise: propagate it into the state the same period
    cov = solve_discrete_lyapunov(aug, np.outer(b, b) * noise_std_n**2)
    # the true force at the next plant step, from the state (contact held)
    c = np.zeros(n + 1)
    c[:n] = step_rows(loop, *nominal).spring_next
    return float(math.sqrt(max(float(c @ cov @ c), 0.0)))


def substep_lag(substeps: int, cutoff_hz: float, period_s: float) -> float:
    """The mean lag, in periods, of the forces a per-substep sensor filter has taken in during
    one period: substep ``j`` (0 = the last) evaluates the contact ``(j + 1) / substeps`` of a
    period before the end and enters the sample with weight ``alpha (1 - alpha)^j``."""
    dt = period_s / substeps
    alpha = 1.0 - math.exp(-2.0 * math.pi * cutoff_hz * dt)
    weights = [alpha * (1.0 - alpha) ** j for j in range(substeps)]
    lags = [(j + 1) / substeps for j in range(substeps)]
    return sum(w * d for w, d in zip(weights, lags, strict=True)) / sum(weights)
