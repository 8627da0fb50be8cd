"""Serial-chain kinematics for the 6-DOF inner loop: FK, geometric Jacobian, DLS inverse kinematics.

A chain is described by standard Denavit-Hartenberg parameters (see
:class:`~fuzzkit.plants.robot_description.Joint`), with joint position and velocity limits and
a tool offset, in a robot description (:mod:`fuzzkit.plants.robot_description`: read from a
small YAML file, or built directly as dataclasses). The ABB IRB 140 ships as
``fuzzkit/data/irb140.yaml`` (``load_robot("irb140")``).

Conventions
-----------
* Standard DH: ``A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` with ``theta_i = q_i + offset_i``;
  the pose of the tool centre point (TCP) is ``A_1 ... A_n T_tool``.
* Poses are 4x4 homogeneous transforms of the TCP in the robot base frame, metres and radians.
* The geometric Jacobian maps joint rates to the TCP twist ``[v; w]`` (linear velocity of the TCP
  then angular velocity), both in the base frame. Its transpose maps a wrench ``[f; m]`` applied
  at the TCP (base frame) to joint torques, ``tau = J^T [f; m]`` (eq. 3 of the paper).
* IK error: ``[p_target - p; log(R_target R^T)]``, so the orientation error is the true angle.

The scalar paths (:meth:`SerialChain.fk`, :meth:`SerialChain.jacobian`, :meth:`SerialChain.ik`)
use plain Python floats because the plant calls them every 4 ms step and numpy's per-call
overhead dominates for 6 joints; the batch paths (:meth:`SerialChain.fk_batch`,
:meth:`SerialChain.jacobian_batch`) are vectorised over many configurations.

Twins: this is the **reference** copy of the 6-DOF forward kinematics, Jacobian, damped least
squares and IK; the compiled loop's copy (:mod:`fuzzkit.plants.arm6_period`) is tested against
it (``tests/test_compiled_loop.py``), so it is kept as a separate implementation on purpose.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.plants.robot_description import RobotDescription, load_robot
from fuzzkit.plants.rotations import Mat3, Vec3, rotation_error

FloatArray = npt.NDArray[np.float64]

# --------------------------------------------------------------------------------------------
# IK result
# --------------------------------------------------------------------------------------------


class IKStatus(enum.Enum):
    """How an inverse-kinematics solve ended."""

    #: position and orientation errors below the tolerances
    CONVERGED = "converged"
    #: no joint motion reduces the error and no joint is at a limit: the pose is outside the
    #: workspace (or, rarely, the seed sits in a local minimum of the error)
    UNREACHABLE = "unreachable"
    #: stalled with one or more joints at a position limit: the pose needs motion past it
    LIMIT = "limit"
    #: still improving when the iteration budget ran out
    MAX_ITERATIONS = "max_iterations"


@dataclass(frozen=True, slots=True)
class IKResult:
    """Outcome of :meth:`SerialChain.ik`: the joints reached and how good they are.

    ``q`` always lies within the joint limits, whatever the status; it is the best configuration
    found, so a caller tracking a path can keep using it when the status is not CONVERGED.
    """

    q: FloatArray
    status: IKStatus
    position_error: float
    orientation_error: float
    iterations: int
    at_limit: tuple[int, ...] = field(default=())

    @property
    def converged(self) -> bool:
        """True when the target pose was reached within tolerance."""
        return self.status is IKStatus.CONVERGED


# --------------------------------------------------------------------------------------------
# The chain
# --------------------------------------------------------------------------------------------

#: One kinematic pass: TCP rotation and position, each joint's axis and origin (base frame).
ChainEval = tuple[Mat3, Vec3, list[Vec3], list[Vec3]]
_Eval = ChainEval


class SerialChain:
    """Kinematics of one robot description: forward, differential and inverse.

    Parameters
    ----------
    robot:
        The description; defaults to the shipped ABB IRB 140.

    Examples
    --------
    >>> chain = SerialChain()
    >>> pose = chain.fk([0, 0, 0, 0, 0, 0])
    >>> [round(v, 3) for v in pose[:3, 3]]
    [0.515, 0.0, 0.712]
    """

    def __init__(self, robot: RobotDescription | None = None) -> None:
        self.robot = robot if robot is not None else load_robot("irb140")
        js = self.robot.joints
        self.dof = len(js)
        self.lower: FloatArray = np.array([j.lower for j in js])
        self.upper: FloatArray = np.array([j.upper for j in js])
        self.max_velocity: FloatArray = np.array([j.max_velocity for j in js])
        self._d = np.array([j.d for j in js])
        self._a = np.array([j.a for j in js])
        self._alpha = np.array([j.alpha for j in js])
        self._offset = np.array([j.offset for j in js])
        # Per-joint constants for the scalar path, precomputed once.
        self._links = [(j.d, j.a, math.cos(j.alpha), math.sin(j.alpha), j.offset) for j in js]
        self._lo = [j.lower for j in js]
        self._hi = [j.upper for j in js]
        tool = self.robot.tool_transform()
        self.tool: FloatArray = tool
        self._tool_r: Mat3 = (
            (tool[0, 0], tool[0, 1], tool[0, 2]),
            (tool[1, 0], tool[1, 1], tool[1, 2]),
            (tool[2, 0], tool[2, 1], tool[2, 2]),
        )
        self._tool_p: Vec3 = (tool[0, 3], tool[1, 3], tool[2, 3])
        self._cache: dict[tuple[float, ...], _Eval] = {}

    # ---- scalar forward kinematics ----------------------------------------------------------

    def _evaluate(self, q: Sequence[float]) -> _Eval:
        """TCP rotation and position, plus each joint's axis and origin (base frame).

        Joint i turns about the z axis of frame i-1, through that frame's origin; those are what
        the geometric Jacobian needs, so one pass gives both FK and J.
        """
        key = tuple(q)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        r00, r01, r02 = 1.0, 0.0, 0.0
        r10, r11, r12 = 0.0, 1.0, 0.0
        r20, r21, r22 = 0.0, 0.0, 1.0
        px = py = pz = 0.0
        axes: list[Vec3] = []
        origins: list[Vec3] = []
        for qi, (d, a, ca, sa, off) in zip(key, self._links, strict=True):
            axes.append((r02, r12, r22))
            origins.append((px, py, pz))
            th = qi + off
            ct, st = math.cos(th), math.sin(th)
            # A = [[ct, -st*ca, st*sa, a*ct], [st, ct*ca, -ct*sa, a*st], [0, sa, ca, d]]
            px += r00 * a * ct + r01 * a * st + r02 * d
            py += r10 * a * ct + r11 * a * st + r12 * d
            pz += r20 * a * ct + r21 * a * st + r22 * d
            n00 = r00 * ct + r01 * st
            n01 = -r00 * st * ca + r01 * ct * ca + r02 * sa
            n02 = r00 * st * sa - r01 * ct * sa + r02 * ca
            n10 = r10 * ct + r11 * st
            n11 = -r10 * st * ca + r11 * ct * ca + r12 * sa
            n12 = r10 * st * sa - r11 * ct * sa + r12 * ca
            n20 = r20 * ct + r21 * st
            n21 = -r20 * st * ca + r21 * ct * ca + r22 * sa
            n22 = r20 * st * sa - r21 * ct * sa + r22 * ca
            r00, r01, r02 = n00, n01, n02
            r10, r11, r12 = n10, n11, n12
            r20, r21, r22 = n20, n21, n22
        (t00, t01, t02), (t10, t11, t12), (t20, t21, t22) = self._tool_r
        tx, ty, tz = self._tool_p
        p: Vec3 = (
            px + r00 * tx + r01 * ty + r02 * tz,
            py + r10 * tx + r11 * ty + r12 * tz,
            pz + r20 * tx + r21 * ty + r22 * tz,
        )
        rot: Mat3 = (
            (
                r00 * t00 + r01 * t10 + r02 * t20,
                r00 * t01 + r01 * t11 + r02 * t21,
                r00 * t02 + r01 * t12 + r02 * t22,
            ),
            (
                r10 * t00 + r11 * t10 + r12 * t20,
                r10 * t01 + r11 * t11 + r12 * t21,
                r10 * t02 + r11 * t12 + r12 * t22,
            ),
            (
                r20 * t00 + r21 * t10 + r22 * t20,
                r20 * t01 + r21 * t11 + r22 * t21,
                r20 * t02 + r21 * t12 + r22 * t22,
            ),
        )
        out: _Eval = (rot, p, axes, origins)
        # A few recent configurations: the plant alternates between the IK iterate and the
        # actual (lagging) joints, and each is asked for again in the next period.
        if len(self._cache) >= 16:
            self._cache.clear()
        self._cache[key] = out
        return out

    def evaluate(self, q: Sequence[float]) -> ChainEval:
        """One kinematic pass for the hot path: ``(R_tcp, p_tcp, joint axes, joint origins)``.

        Tuples of floats in the base frame; ``q`` is not checked (use :meth:`fk` for user
        input). Feed the result to :meth:`jacobian_of` and :meth:`frames_of` to avoid
        recomputing.
        """
        return self._evaluate(q)

    def jacobian_of(self, ev: ChainEval) -> FloatArray:
        """Geometric Jacobian (6 x dof) from an :meth:`evaluate` result."""
        return np.array(self._jacobian_rows(ev))

    def frames_of(self, ev: ChainEval) -> FloatArray:
        """Arm polyline (base, DH frame origins, flange, TCP) from an :meth:`evaluate` result."""
        rot, p, _, origins = ev
        # flange = TCP minus the tool offset: p6 = p - R R_t^T t
        t_rt = self._tool_r
        tp = self._tool_p
        back = [t_rt[0][i] * tp[0] + t_rt[1][i] * tp[1] + t_rt[2][i] * tp[2] for i in range(3)]
        p6 = [
            p[i] - (rot[i][0] * back[0] + rot[i][1] * back[1] + rot[i][2] * back[2])
            for i in range(3)
        ]
        return np.array([*origins, p6, p])

    def _check_q(self, q: Sequence[float] | FloatArray) -> list[float]:
        values = [float(v) for v in np.asarray(q, dtype=float).reshape(-1)]
        if len(values) != self.dof:
            raise ValueError(
                f"{self.robot.name}: expected {self.dof} joint values (got {len(values)})"
            )
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"{self.robot.name}: joint values must be finite (got {values})")
        return values

    def fk(self, q: Sequence[float] | FloatArray) -> FloatArray:
        """Return the 4x4 pose of the TCP in the base frame for joint positions ``q`` (rad).

        Raises
        ------
        ValueError
            If ``q`` has the wrong length or non-finite values.
        """
        rot, p, _, _ = self._evaluate(self._check_q(q))
        out = np.eye(4)
        out[:3, :3] = rot
        out[:3, 3] = p
        return out

    def frames(self, q: Sequence[float] | FloatArray) -> FloatArray:
        """Return the origins of the base, every DH frame and the TCP: shape ``(dof + 2, 3)``.

        This is the polyline drawn as the arm in recordings.
        """
        return self.frames_of(self._evaluate(self._check_q(q)))

    def jacobian(self, q: Sequence[float] | FloatArray) -> FloatArray:
        """Return the 6 x dof geometric Jacobian at the TCP, base frame, rows ``[v; w]``.

        Raises
        ------
        ValueError
            If ``q`` has the wrong length or non-finite values.
        """
        return np.array(self._jacobian_rows(self._evaluate(self._check_q(q))))

    @staticmethod
    def _jacobian_rows(ev: _Eval) -> list[list[float]]:
        _, (px, py, pz), axes, origins = ev
        rows: list[list[float]] = [[], [], [], [], [], []]
        for (zx, zy, zz), (ox, oy, oz) in zip(axes, origins, strict=True):
            dx, dy, dz = px - ox, py - oy, pz - oz
            rows[0].append(zy * dz - zz * dy)
            rows[1].append(zz * dx - zx * dz)
            rows[2].append(zx * dy - zy * dx)
            rows[3].append(zx)
            rows[4].append(zy)
            rows[5].append(zz)
        return rows

    def joint_torques(
        self, q: Sequence[float] | FloatArray, wrench: Sequence[float] | FloatArray
    ) -> FloatArray:
        """Return ``tau_e = J(q)^T w`` for a wrench ``[f; m]`` at the TCP in the base frame."""
        w = np.asarray(wrench, dtype=float).reshape(-1)
        if w.shape != (6,):
            raise ValueError(f"wrench must have 6 components [fx fy fz mx my mz] (got {w.size})")
        tau: FloatArray = self.jacobian(q).T @ w
        return tau

    # ---- batch ------------------------------------------------------------------------------

    def _batch_frames(self, qs: FloatArray) -> FloatArray:
        """All frames for a batch: shape ``(N, dof + 1, 4, 4)``, frame 0 the base."""
        q = np.asarray(qs, dtype=float)
        if q.ndim != 2 or q.shape[1] != self.dof:
            raise ValueError(
                f"{self.robot.name}: expected joint batch of shape (N, {self.dof}) (got {q.shape})"
            )
        n = q.shape[0]
        th = q + self._offset
        ct, st = np.cos(th), np.sin(th)
        ca, sa = np.cos(self._alpha), np.sin(self._alpha)
        a = np.zeros((n, self.dof, 4, 4))
        a[..., 0, 0] = ct
        a[..., 0, 1] = -st * ca
        a[..., 0, 2] = st * sa
        a[..., 0, 3] = self._a * ct
        a[..., 1, 0] = st
        a[..., 1, 1] = ct * ca
        a[..., 1, 2] = -ct * sa
        a[..., 1, 3] = self._a * st
        a[..., 2, 1] = sa
        a[..., 2, 2] = ca
        a[..., 2, 3] = self._d
        a[..., 3, 3] = 1.0
        out = np.empty((n, self.dof + 1, 4, 4))
        out[:, 0] = np.eye(4)
        for i in range(self.dof):
            out[:, i + 1] = out[:, i] @ a[:, i]
        return out

    def fk_batch(self, qs: FloatArray) -> FloatArray:
        """Return TCP poses for many configurations: ``(N, dof)`` -> ``(N, 4, 4)``."""
        return self._batch_frames(qs)[:, -1] @ self.tool

    def jacobian_batch(self, qs: FloatArray) -> FloatArray:
        """Return geometric Jacobians for many configurations: ``(N, dof)`` -> ``(N, 6, dof)``."""
        frames = self._batch_frames(qs)
        tcp = (frames[:, -1] @ self.tool)[:, :3, 3]
        z = frames[:, :-1, :3, 2]  # (N, dof, 3): joint i turns about z of frame i-1
        o = frames[:, :-1, :3, 3]
        jv = np.cross(z, tcp[:, None, :] - o)
        return np.concatenate([jv, z], axis=2).transpose(0, 2, 1)

    # ---- inverse kinematics -------------------------------------------------------------------

    def within_limits(self, q: Sequence[float] | FloatArray, tol: float = 0.0) -> bool:
        """True when every joint lies within its position limits (widened by ``tol``)."""
        v = np.asarray(q, dtype=float)
        return bool(np.all(v >= self.lower - tol) and np.all(v <= self.upper + tol))

    def ik(
        self,
        target: FloatArray,
        seed: Sequence[float] | FloatArray,
        *,
        position_tolerance: float = 1e-9,
        orientation_tolerance: float = 1e-9,
        max_iterations: int = 100,
        max_step: float = 0.5,
        position_only: bool = False,
    ) -> IKResult:
        """Solve for joints that put the TCP at ``target``, starting from ``seed``.

        Damped least squares (Levenberg-Marquardt) on the 6-D pose error
        ``e = [p_t - p; log(R_t R^T)]``: ``dq = J^T (J J^T + lambda^2 I)^-1 e`` with
        ``lambda^2 = 0.5 |e|^2 + mu``. The error term (Sugihara's choice) makes steps near-Newton
        close to the solution (quadratic convergence, so 1e-9 costs one more iteration than
        1e-5); ``mu`` adapts like Levenberg-Marquardt: a step that does not reduce the error is
        rejected and retried with 10x damping, which is what keeps the steps bounded near
        singularities (wrist aligned, arm stretched) where J J^T loses rank. Joints are clamped
        to their limits; a joint at a limit whose step pushes outwards is frozen for that step
        so the others compensate (an active set), instead of the solver stalling on the clamp.

        Parameters
        ----------
        target:
            4x4 TCP pose in the base frame.
        seed:
            Starting joints (clamped to the limits): the previous solution when tracking a path.
        position_tolerance, orientation_tolerance:
            Convergence thresholds in metres and radians.
        max_iterations:
            Budget of accepted-or-rejected steps.
        max_step:
            Largest change of any joint in one step (rad); larger steps are scaled down.
        position_only:
            Solve for the TCP position only (orientation free).

        Returns
        -------
        IKResult
            Never raises for an unreachable pose: the status says what happened.

        Raises
        ------
        ValueError
            If ``target`` is not a finite 4x4 matrix or ``seed`` has the wrong length.
        """
        t = np.asarray(target, dtype=float)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ValueError(f"target must be a finite 4x4 pose (got shape {t.shape})")
        rows = t.tolist()
        rt: Mat3 = (
            (rows[0][0], rows[0][1], rows[0][2]),
            (rows[1][0], rows[1][1], rows[1][2]),
            (rows[2][0], rows[2][1], rows[2][2]),
        )
        pt: Vec3 = (rows[0][3], rows[1][3], rows[2][3])
        return self.ik_fast(
            rt,
            pt,
            self._check_q(seed),
            position_tolerance=position_tolerance,
            orientation_tolerance=orientation_tolerance,
            max_iterations=max_iterations,
            max_step=max_step,
            position_only=position_only,
        )

    def ik_restarts(
        self,
        target: FloatArray,
        seed: Sequence[float] | FloatArray | None = None,
        *,
        restarts: int = 32,
        rng_seed: int = 0,
        **options: Any,
    ) -> IKResult:
        """:meth:`ik` from ``seed``, then from random seeds within the limits until one converges.

        Damped least squares is local: from a seed far from the answer it can stall against a
        joint limit on the wrong branch (about half the time for uniformly random seeds on the
        IRB 140). Restarting from other seeds finds a solution when one exists; the random
        seeds come from ``numpy.random.default_rng(rng_seed)``, so the result is deterministic.

        Returns
        -------
        IKResult
            The first converged result, else the one with the smallest error.
        """
        first = self.ik(target, self.lower * 0.0 if seed is None else seed, **options)
        if first.converged:
            return first
        best = first
        rng = np.random.default_rng(rng_seed)
        for _ in range(restarts):
            res = self.ik(target, rng.uniform(self.lower, self.upper), **options)
            if res.converged:
                return res
            if res.position_error + res.orientation_error < (
                best.position_error + best.orientation_error
            ):
                best = res
        return best

    def ik_fast(
        self,
        rotation: Mat3,
        position: Vec3,
        seed: Sequence[float],
        *,
        position_tolerance: float = 1e-9,
        orientation_tolerance: float = 1e-9,
        max_iterations: int = 100,
        max_step: float = 0.5,
        position_only: bool = False,
    ) -> IKResult:
        """:meth:`ik` for the plant's hot path: target as tuples, nothing checked.

        ``rotation`` (3x3 row tuples) and ``position`` give the TCP target; ``seed`` must hold
        ``dof`` finite floats (it is clamped to the limits). Use :meth:`ik` for user input.
        """
        lo, hi = self._lo, self._hi
        q = [min(max(v, lo[i]), hi[i]) for i, v in enumerate(seed)]
        return self._solve(
            rotation,
            position,
            q,
            position_tolerance,
            orientation_tolerance,
            max_iterations,
            max_step,
            position_only,
        )

    def _error(
        self, rt: Mat3, pt: Vec3, ev: _Eval, position_only: bool
    ) -> tuple[list[float], float, float]:
        rot, p, _, _ = ev
        ep = [pt[0] - p[0], pt[1] - p[1], pt[2] - p[2]]
        eo = [0.0, 0.0, 0.0] if position_only else list(rotation_error(rt, rot))
        return (
            ep + eo,
            math.sqrt(ep[0] ** 2 + ep[1] ** 2 + ep[2] ** 2),
            math.sqrt(eo[0] ** 2 + eo[1] ** 2 + eo[2] ** 2),
        )

    def _solve(
        self,
        rt: Mat3,
        pt: Vec3,
        q: list[float],
        tol_p: float,
        tol_o: float,
        max_iterations: int,
        max_step: float,
        position_only: bool,
    ) -> IKResult:
        lo, hi = self._lo, self._hi
        ev = self._evaluate(q)
        e, ep, eo = self._error(rt, pt, ev, position_only)
        cost = ep * ep + eo * eo
        mu = 1e-9
        slow = 0
        suspect = False
        iterations = 0
        status = IKStatus.MAX_ITERATIONS
        n = self.dof
        rows_used = 3 if position_only else 6
        while True:
            if ep <= tol_p and eo <= tol_o:
                status = IKStatus.CONVERGED
                break
            if iterations >= max_iterations:
                break
            iterations += 1
            jac = np.array(self._jacobian_rows(ev)[:rows_used])
            # Active set: freeze joints sitting at a limit whose unconstrained step points out.
            lam2 = 0.5 * cost + mu
            err = np.array(e[:rows_used])
            dq = self._dls(jac, err, lam2)
            blocked = [
                i
                for i in range(n)
                if (q[i] <= lo[i] and dq[i] < 0.0) or (q[i] >= hi[i] and dq[i] > 0.0)
            ]
            if blocked:
                jac[:, blocked] = 0.0
                dq = self._dls(jac, err, lam2)
            # Stationary point test: the error is (nearly) orthogonal to every direction the free
            # joints can move the TCP, so no step can reduce it: the closest reachable pose.
            # Only asked once progress falters, to keep the usual tracking step cheap.
            if suspect:
                grad = jac.T @ err
                if float(grad @ grad) <= 1e-12 * float(np.sum(jac * jac)) * cost:
                    status = IKStatus.LIMIT if blocked else IKStatus.UNREACHABLE
                    break
            big = max(abs(v) for v in dq)
            scale = max_step / big if big > max_step else 1.0
            q_new = [min(max(q[i] + scale * dq[i], lo[i]), hi[i]) for i in range(n)]
            ev_new = self._evaluate(q_new)
            e_new, ep_new, eo_new = self._error(rt, pt, ev_new, position_only)
            cost_new = ep_new * ep_new + eo_new * eo_new
            if cost_new < cost:
                # A run of accepted steps that barely lower the error is a stationary point
                # approached slowly (the closest pose to an unreachable target): stop there
                # instead of spending the whole budget.
                slow = slow + 1 if cost_new > cost * (1.0 - 1e-6) else 0
                suspect = slow > 0
                q, ev, e, ep, eo, cost = q_new, ev_new, e_new, ep_new, eo_new, cost_new
                mu = max(mu * 0.1, 1e-12)
                if slow >= 5:
                    status = IKStatus.LIMIT if self._at_limit(q) else IKStatus.UNREACHABLE
                    break
            else:
                mu *= 10.0
                suspect = True
                # Damping this large means no step of any useful length lowers the error:
                # a stationary point that is not the target.
                if mu > 1e4:
                    at = self._at_limit(q)
                    status = IKStatus.LIMIT if at else IKStatus.UNREACHABLE
                    break
        return IKResult(
            q=np.array(q),
            status=status,
            position_error=ep,
            orientation_error=eo,
            iterations=iterations,
            at_limit=self._at_limit(q),
        )

    @staticmethod
    def _dls(jac: FloatArray, err: FloatArray, lam2: float) -> list[float]:
        a = jac @ jac.T
        a.flat[:: a.shape[0] + 1] += lam2
        return [float(v) for v in jac.T @ np.linalg.solve(a, err)]

    def _at_limit(self, q: Sequence[float], tol: float = 1e-12) -> tuple[int, ...]:
        return tuple(i for i, v in enumerate(q) if v <= self._lo[i] + tol or v >= self._hi[i] - tol)
