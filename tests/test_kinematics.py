"""Tests of fuzzkit.plants.kinematics: FK against hand geometry, Jacobian against finite
differences, IK round trips and statuses, the robot description loader."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from fuzzkit.errors import ConfigError
from fuzzkit.plants.kinematics import IKStatus, SerialChain
from fuzzkit.plants.robot_description import Joint, RobotDescription, load_robot
from fuzzkit.plants.rotations import rotation_error

Arr = npt.NDArray[np.float64]
DEG = math.pi / 180.0


def rot(axis: str, angle: float) -> Arr:
    """Elementary rotation matrix about a base axis (written out, independent of the code)."""
    c, s = math.cos(angle), math.sin(angle)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def pose(r: Arr, p: tuple[float, float, float]) -> Arr:
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = p
    return t


@pytest.fixture(scope="module")
def chain() -> SerialChain:
    return SerialChain()


# The IRB 140 drawn at its calibration pose: shoulder axis at x=0.070, z=0.352; upper arm 0.360
# up; forearm 0.380 forward; flange 0.065 further; tool0 has z forward, x down = Ry(+90 deg).
R0 = rot("y", math.pi / 2)


def poe_reference(q: Arr) -> Arr:
    """FK as a product of exponentials about the axes seen on the drawing at q = 0.

    Independent of the DH code: each joint is a rotation about a fixed base-frame axis through
    a point read off the drawing, applied outermost-first: T = e^{q1 S1} ... e^{q6 S6} T0.
    """
    axes = [
        ("z", (0.0, 0.0, 0.0)),
        ("y", (0.070, 0.0, 0.352)),
        ("y", (0.070, 0.0, 0.712)),
        ("x", (0.070, 0.0, 0.712)),
        ("y", (0.450, 0.0, 0.712)),
        ("x", (0.450, 0.0, 0.712)),
    ]
    t = np.eye(4)
    for qi, (ax, point) in zip(q, axes, strict=True):
        r = rot(ax, float(qi))
        pt = np.array(point)
        g = np.eye(4)
        g[:3, :3] = r
        g[:3, 3] = pt - r @ pt
        t = t @ g
    return t @ pose(R0, (0.515, 0.0, 0.712))


@pytest.mark.parametrize(
    "q, expected",
    [
        # calibration pose
        ([0, 0, 0, 0, 0, 0], pose(R0, (0.515, 0.0, 0.712))),
        # base turned 90 deg: the whole arm now points along +y
        ([90, 0, 0, 0, 0, 0], pose(rot("z", math.pi / 2) @ R0, (0.0, 0.515, 0.712))),
        # upper arm tilted forward to horizontal: elbow at x=0.43, forearm hangs down
        ([0, 90, 0, 0, 0, 0], pose(rot("y", math.pi), (0.430, 0.0, 0.352 - 0.380 - 0.065))),
        # forearm raised vertical: the arm stands straight up, 0.352+0.360+0.380+0.065 high
        ([0, 0, -90, 0, 0, 0], pose(np.eye(3), (0.070, 0.0, 1.157))),
        # wrist bent down 90 deg: flange 0.065 below the wrist centre, tool0 z pointing down
        ([0, 0, 0, 0, 90, 0], pose(rot("y", math.pi), (0.450, 0.0, 0.647))),
        # forearm rolled 90 deg then wrist bent: the flange points to +y
        (
            [0, 0, 0, 90, 90, 0],
            pose(rot("x", math.pi / 2) @ rot("y", math.pi), (0.450, 0.065, 0.712)),
        ),
        # flange roll only turns the tool about its own axis (+x here)
        ([0, 0, 0, 0, 0, 90], pose(rot("x", math.pi / 2) @ R0, (0.515, 0.0, 0.712))),
    ],
)
def test_fk_matches_hand_computed_poses(chain: SerialChain, q: list[float], expected: Arr) -> None:
    got = chain.fk(np.array(q, dtype=float) * DEG)
    np.testing.assert_allclose(got, expected, atol=1e-12)


def test_fk_matches_product_of_exponentials_on_random_configurations(chain: SerialChain) -> None:
    rng = np.random.default_rng(7)
    qs = rng.uniform(chain.lower, chain.upper, (200, 6))
    for q in qs:
        np.testing.assert_allclose(chain.fk(q), poe_reference(q), atol=1e-12)
    # the batch path gives the same poses
    np.testing.assert_allclose(
        chain.fk_batch(qs), np.array([poe_reference(q) for q in qs]), atol=1e-12
    )


def test_tool_offset_moves_the_tcp_along_the_flange_axis() -> None:
    robot = load_robot("irb140").with_tool((0.0, 0.0, 0.12))
    chain = SerialChain(robot)
    # at q = 0 the flange z axis points along base +x
    np.testing.assert_allclose(chain.fk(np.zeros(6))[:3, 3], [0.635, 0.0, 0.712], atol=1e-12)
    # wrist bent down: the tool hangs 0.065 + 0.12 below the wrist centre
    q = np.array([0, 0, 0, 0, 90, 0]) * DEG
    np.testing.assert_allclose(chain.fk(q)[:3, 3], [0.450, 0.0, 0.712 - 0.185], atol=1e-12)


def numeric_jacobian(chain: SerialChain, q: Arr, h: float = 1e-6) -> Arr:
    jac = np.zeros((6, q.size))
    for i in range(q.size):
        dq = np.zeros_like(q)
        dq[i] = h
        tp, tm = chain.fk(q + dq), chain.fk(q - dq)
        jac[:3, i] = (tp[:3, 3] - tm[:3, 3]) / (2 * h)
        # angular velocity: log(R(q+h) R(q-h)^T) / 2h
        jac[3:, i] = np.array(rotation_error(tp[:3, :3].tolist(), tm[:3, :3].tolist())) / (2 * h)
    return jac


def test_jacobian_matches_finite_differences() -> None:
    chain = SerialChain(load_robot("irb140").with_tool((0.01, -0.02, 0.15), (0.1, 0.2, 0.3)))
    rng = np.random.default_rng(3)
    qs = rng.uniform(chain.lower, chain.upper, (50, 6))
    batch = chain.jacobian_batch(qs)
    for k, q in enumerate(qs):
        num = numeric_jacobian(chain, q)
        np.testing.assert_allclose(chain.jacobian(q), num, atol=1e-8)
        np.testing.assert_allclose(batch[k], num, atol=1e-8)


def test_joint_torques_equal_virtual_work(chain: SerialChain) -> None:
    # tau . dq must equal the work of the wrench along the TCP displacement dq causes
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = rng.uniform(chain.lower, chain.upper)
        w = rng.normal(0.0, 10.0, 6)
        tau = chain.joint_torques(q, w)
        dq = rng.normal(0.0, 1.0, 6) * 1e-6
        tp, tm = chain.fk(q + dq), chain.fk(q - dq)
        dp = (tp[:3, 3] - tm[:3, 3]) / 2
        dth = np.array(rotation_error(tp[:3, :3].tolist(), tm[:3, :3].tolist())) / 2
        assert tau @ dq == pytest.approx(w[:3] @ dp + w[3:] @ dth, rel=1e-6, abs=1e-12)


def test_ik_round_trip_on_1000_random_reachable_poses(chain: SerialChain) -> None:
    rng = np.random.default_rng(2024)
    qs = rng.uniform(chain.lower, chain.upper, (1000, 6))
    targets = chain.fk_batch(qs)
    failures = []
    for q, target in zip(qs, targets, strict=True):
        seed = np.clip(q + rng.uniform(-0.3, 0.3, 6), chain.lower, chain.upper)
        res = chain.ik(target, seed)
        assert chain.within_limits(res.q)
        # check against an independent FK, not the solver's own error bookkeeping
        got = poe_reference(res.q)
        pos_err = float(np.linalg.norm(got[:3, 3] - target[:3, 3]))
        ori_err = float(
            np.linalg.norm(rotation_error(target[:3, :3].tolist(), got[:3, :3].tolist()))
        )
        if not (res.converged and pos_err < 1e-6 and ori_err < 1e-6):
            failures.append((q, res.status, pos_err, ori_err))
        assert res.position_error == pytest.approx(pos_err, abs=1e-9)
    assert not failures, f"{len(failures)} of 1000 poses failed, first: {failures[0]}"


def test_ik_from_far_seeds_never_leaves_the_limits(chain: SerialChain) -> None:
    rng = np.random.default_rng(5)
    statuses = set()
    for _ in range(100):
        target = chain.fk(rng.uniform(chain.lower, chain.upper))
        res = chain.ik(target, rng.uniform(chain.lower, chain.upper), max_iterations=60)
        statuses.add(res.status)
        assert chain.within_limits(res.q)
        if res.converged:
            assert res.position_error < 1e-6 and res.orientation_error < 1e-6
        else:
            assert res.position_error + res.orientation_error > 1e-9
    assert IKStatus.CONVERGED in statuses


def test_ik_reports_an_unreachable_pose(chain: SerialChain) -> None:
    target = pose(np.eye(3), (1.5, 0.0, 0.5))  # reach is about 0.81 m
    res = chain.ik(target, np.zeros(6))
    assert res.status is IKStatus.UNREACHABLE
    assert res.position_error > 0.5
    assert res.iterations < 100  # it stops on a stall, not on the budget
    assert chain.within_limits(res.q)


def test_ik_reports_a_joint_limit() -> None:
    robot = load_robot("irb140")
    tight = Joint(**{**_joint_kwargs(robot.joints[0]), "lower": -10 * DEG, "upper": 10 * DEG})
    chain = SerialChain(RobotDescription("tight", (tight, *robot.joints[1:])))
    # the pose with the arm turned to the side, only reachable with axis 1 near 90 deg
    target = SerialChain(robot).fk(np.array([90, 10, 10, 0, 40, 0]) * DEG)
    res = chain.ik(target, np.zeros(6))
    assert res.status is IKStatus.LIMIT
    assert 0 in res.at_limit
    assert chain.within_limits(res.q)


def test_ik_reports_running_out_of_iterations(chain: SerialChain) -> None:
    target = chain.fk(np.array([40, 30, -20, 10, 50, 20]) * DEG)
    res = chain.ik(target, np.zeros(6), max_iterations=1)
    assert res.status is IKStatus.MAX_ITERATIONS
    assert res.iterations == 1


def test_ik_position_only_ignores_orientation(chain: SerialChain) -> None:
    target = chain.fk(np.array([10, 20, 10, 0, 30, 0]) * DEG)
    target[:3, :3] = np.eye(3)  # an orientation this position need not have
    res = chain.ik(target, np.zeros(6), position_only=True)
    assert res.converged
    np.testing.assert_allclose(chain.fk(res.q)[:3, 3], target[:3, 3], atol=1e-9)


def _joint_kwargs(j: Joint) -> dict[str, object]:
    return {f: getattr(j, f) for f in Joint.__dataclass_fields__}


def test_shipped_irb140_description_matches_the_data_sheet() -> None:
    robot = load_robot("irb140")
    assert [j.d for j in robot.joints] == [0.352, 0, 0, 0.380, 0, 0.065]
    assert [j.a for j in robot.joints] == [0.070, 0.360, 0, 0, 0, 0]
    np.testing.assert_allclose(
        [(j.lower / DEG, j.upper / DEG) for j in robot.joints],
        [(-180, 180), (-90, 110), (-230, 50), (-200, 200), (-115, 115), (-400, 400)],
    )
    np.testing.assert_allclose(
        [j.max_velocity / DEG for j in robot.joints], [200, 200, 260, 360, 360, 450]
    )


@pytest.mark.parametrize(
    "text, match",
    [
        ("name: x\njoints: []\n", r"'joints' must be a non-empty list"),
        (
            "name: x\njoints:\n  - {d: 0, a: 0, alpha: 0, limits: [1, -1], max_velocity: 1}\n",
            r"x\.yaml:3: joint 1: limits must be \[lower, upper\] with lower < upper",
        ),
        (
            "name: x\njoints:\n  - {d: 0, a: 0, alpha: 0, limits: [-1, 1], max_velocity: 0}\n",
            r"max_velocity must be > 0",
        ),
        (
            "name: x\njoints:\n  - {d: zero, a: 0, alpha: 0, limits: [-1, 1], max_velocity: 1}\n",
            r"'d' must be a finite number \(got 'zero'\)",
        ),
        (
            "name: x\ncolour: red\n"
            "joints: [{d: 0, a: 0, alpha: 0, limits: [-1, 1], max_velocity: 1}]\n",
            r"x\.yaml:2: unknown key 'colour'",
        ),
        ("name: x\nangle_unit: grad\njoints: []\n", r"2 problems found"),
        ("name: [x\n", r"x\.yaml:2:1: invalid YAML"),
        # the located-YAML reader's checks (shared with rule bases and scenarios)
        ("name: x\nname: y\njoints: []\n", r"x\.yaml:2:1: duplicate key 'name'"),
        ("name: x\non: 1\njoints: []\n", r"x\.yaml:2:1: expected a name as key, got on"),
        ("name: x\x01\njoints: []\n", r"x\.yaml:1:8: control character U\+0001"),
        ("name: x\njoints: [{d: 1" + "0" * 320 + "}]\n", r"x\.yaml:2:14: integer of 321 digits"),
        (
            "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
            + "".join(
                f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
                for p, c in zip("abcde", "bcdef", strict=True)
            ),
            r"x\.yaml: the document expands to more than 100000 nodes",
        ),
    ],
)
def test_bad_robot_descriptions_get_located_errors(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "x.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=match):
        load_robot(path)


def test_unknown_robot_name_is_a_clear_error() -> None:
    with pytest.raises(ConfigError, match="unknown robot 'irb9999'"):
        load_robot("irb9999")


@pytest.mark.parametrize("q", [np.zeros(5), np.array([0, 0, 0, 0, 0, np.nan])])
def test_fk_rejects_bad_joint_vectors(chain: SerialChain, q: Arr) -> None:
    with pytest.raises(ValueError, match="joint values"):
        chain.fk(q)


@pytest.mark.parametrize(
    "q_deg",
    [
        [10, 20, -30, 40, 0, 50],  # wrist singular: axes 4 and 6 aligned (q5 = 0)
        [0, 40, -90, 0, 30, 0],  # elbow singular: forearm in line with the upper arm
        [0, 0, 0, 0, 0, 0],  # both at once (calibration pose)
    ],
)
def test_ik_near_singularities_converges_with_bounded_steps(
    chain: SerialChain, q_deg: list[float]
) -> None:
    q_star = np.array(q_deg, dtype=float) * DEG
    assert np.linalg.svd(chain.jacobian(q_star), compute_uv=False)[-1] < 1e-2  # really singular
    rng = np.random.default_rng(8)
    for _ in range(10):
        seed = q_star + rng.uniform(-0.05, 0.05, 6)
        target = chain.fk(q_star)
        res = chain.ik(target, seed, max_step=0.5)
        # reaching the pose is what counts (the joints may differ along the singular direction)
        assert res.converged, res
        got = chain.fk(res.q)
        assert np.linalg.norm(got[:3, 3] - target[:3, 3]) < 1e-6
        # damping keeps the solution near the seed instead of flying off along the null space
        assert np.max(np.abs(res.q - seed)) < 0.5
    # tracking straight through the wrist singularity: one warm-started solve per 4 ms step
    q = q_star - np.array([0, 0, 0, 0, 0.05, 0])
    start = chain.fk(q)
    for k in range(50):  # the tool moves 0.2 mm per step along its own axis
        t = start.copy()
        t[:3, 3] += start[:3, 2] * 2e-4 * k
        res = chain.ik(t, q, max_iterations=4, position_tolerance=1e-7, orientation_tolerance=1e-7)
        assert res.status in (IKStatus.CONVERGED, IKStatus.MAX_ITERATIONS)
        assert np.max(np.abs(res.q - q)) < 0.1  # no jump
        q = res.q


def test_ik_restarts_find_poses_from_a_fixed_home_seed(chain: SerialChain) -> None:
    rng = np.random.default_rng(99)
    home = np.array([0.0, 0.3, 0.3, 0.0, 0.9, math.pi])
    for _ in range(100):
        target = chain.fk(rng.uniform(chain.lower, chain.upper))
        res = chain.ik_restarts(target, home, restarts=40)
        assert res.converged
        assert chain.within_limits(res.q)
        got = poe_reference(res.q)
        assert np.linalg.norm(got[:3, 3] - target[:3, 3]) < 1e-6
    # an unreachable pose still ends with a clear status after every restart
    res = chain.ik_restarts(pose(np.eye(3), (1.5, 0.0, 0.5)), home, restarts=3)
    assert res.status in (IKStatus.UNREACHABLE, IKStatus.LIMIT)
