"""``fuzzkit replay --forces BAG`` (issue 33 item 8): a ROS 2 bag, written here with rosbags' own
writer in both storage formats, with gaps, decoys, NaN and out-of-order recording, replays to
exactly what the same samples give as CSV; malformed bags are clear errors."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from _replay_logs import SPEC, SPEC_PI, read_out, run_cli, write_log

from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.sensor_logs import hostile_log

rosbag2 = pytest.importorskip("rosbags.rosbag2", reason="rosbags is in the dev lock")
from rosbags.typesys import Stores, get_typestore  # noqa: E402

STORE = get_typestore(Stores.LATEST)
T = STORE.types
START_NS = 1_700_000_000_123_456_789  # a real clock's stamp, not a multiple of the period
PERIOD_NS = 4_000_000  # both example specs run at 4 ms
DOWN = (1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0)


def _stamp(ns: int) -> Any:
    return T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def _header(ns: int) -> Any:
    return T["std_msgs/msg/Header"](stamp=_stamp(ns), frame_id="ft_sensor")


def _vec(v: Any) -> Any:
    return T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))


def wrench(ns: int, f: Any) -> Any:
    w = T["geometry_msgs/msg/Wrench"](force=_vec(f), torque=_vec((0.0, 0.0, 0.0)))
    return T["geometry_msgs/msg/WrenchStamped"](header=_header(ns), wrench=w)


def quaternion(ns: int, q: Any) -> Any:
    qm = T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3])
    return T["geometry_msgs/msg/QuaternionStamped"](header=_header(ns), quaternion=qm)


def write_bag(
    path: Path, storage: str, topics: dict[str, tuple[str, list[tuple[int, Any]]]]
) -> None:
    """A bag with ``{topic: (msgtype, [(receive time ns, message), ...])}``, each topic's
    messages written in the order given."""
    plugin = {"sqlite3": rosbag2.StoragePlugin.SQLITE3, "mcap": rosbag2.StoragePlugin.MCAP}
    with rosbag2.Writer(path, version=9, storage_plugin=plugin[storage]) as writer:
        for topic, (msgtype, msgs) in topics.items():
            conn = writer.add_connection(topic, msgtype, typestore=STORE)
            for t, msg in msgs:
                writer.write(conn, t, STORE.serialize_cdr(msg, msgtype))


def scattered(
    samples: npt.NDArray[np.float64], seed: int, make: Any
) -> tuple[list[tuple[int, Any]], list[bool]]:
    """Messages for ``samples`` (one per period): each stamped up to 3 ms before its grid time,
    some with an older decoy in the same period (the later one is held), some dropped (a gap:
    that period is missing), two recorded out of stamp order. Also which grid rows have one."""
    rng = np.random.default_rng(seed)
    n = len(samples)
    msgs: list[tuple[int, Any]] = []
    present = []
    for k in range(n):
        grid = START_NS + k * PERIOD_NS
        first_or_last = k in (0, n - 1)  # the grid runs from the first stamp to the last
        if not first_or_last and rng.random() < 0.12:
            present.append(False)
            continue
        offset = 0 if first_or_last else int(rng.choice([0, 1_000_000, 2_500_000, 3_000_000]))
        if not first_or_last and rng.random() < 0.2:
            decoy = samples[k] + 100.0  # replaced before the grid time: never seen
            msgs.append((grid - 3_900_000 + 500_000, make(grid - 3_900_000, decoy)))
        msgs.append((grid - offset + 500_000, make(grid - offset, samples[k])))
        present.append(True)
    # the recorder received message 11 before message 10: its order is not the stamps'
    (t10, m10), (t11, m11) = msgs[10], msgs[11]
    msgs[10], msgs[11] = (t10, m11), (t11, m10)
    return msgs, present


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_replays_as_the_same_samples_in_csv(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], storage: str
) -> None:
    spec = load_spec(SPEC_PI)
    forces, _ = hostile_log(spec, n=80, seed=4)  # NaN, inf, spikes, a trip
    msgs, present = scattered(forces, seed=1, make=wrench)
    bag = tmp_path / "bag"
    write_bag(bag, storage, {"/ft/wrench": ("geometry_msgs/msg/WrenchStamped", msgs)})
    expected = np.where(np.array(present)[:, None], forces, math.nan)
    assert not all(present) and np.isnan(forces).any()  # the log has both kinds of hole
    csv = tmp_path / "log.csv"
    write_log(csv, expected, np.tile(DOWN, (len(forces), 1)))
    frame = ",".join(repr(v) for v in DOWN)
    outs = {}
    for name, source, extra in (
        ("bag", str(bag), ["--topic", "/ft/wrench", "--frame-rotation", frame]),
        ("csv", str(csv), []),
    ):
        out = tmp_path / f"u_{name}.csv"
        code, stdout, err = run_cli(
            capsys, "replay", str(SPEC_PI), "--forces", source, "--out", str(out), *extra
        )
        assert code == 0, err
        assert f"{len(forces)} samples replayed" in stdout
        outs[name] = read_out(out)
    assert outs["bag"][0] == outs["csv"][0] == ["t", "ux", "uy", "uz", "status"]
    np.testing.assert_array_equal(outs["bag"][1], outs["csv"][1])
    # the storage file alone (.db3 or .mcap) is a bag too
    (file,) = [p for p in bag.iterdir() if p.suffix in (".db3", ".mcap")]
    out = tmp_path / "u_file.csv"
    argv = ["--topic", "/ft/wrench", "--frame-rotation", frame, "--out", str(out)]
    assert run_cli(capsys, "replay", str(SPEC_PI), "--forces", str(file), *argv)[0] == 0
    np.testing.assert_array_equal(read_out(out)[1], outs["csv"][1])


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_the_tool_rotation_from_a_second_topic(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], storage: str
) -> None:
    from scipy.spatial.transform import Rotation

    spec = load_spec(SPEC)
    forces, _ = hostile_log(spec, n=80, seed=6)
    n = len(forces)
    # the tool pointing down (a half turn about x) swinging by up to 40 degrees about x
    angle = math.pi + np.radians(40.0) * np.sin(np.arange(n) * 0.15)
    quats = np.column_stack([np.sin(angle / 2), np.zeros(n), np.zeros(n), np.cos(angle / 2)])
    fmsgs, fpresent = scattered(forces, seed=2, make=wrench)
    qmsgs, qpresent = scattered(quats, seed=3, make=quaternion)
    bag = tmp_path / "bag"
    write_bag(
        bag,
        storage,
        {
            "/ft/wrench": ("geometry_msgs/msg/WrenchStamped", fmsgs),
            "/tool/orientation": ("geometry_msgs/msg/QuaternionStamped", qmsgs),
        },
    )
    rot = Rotation.from_quat(quats).as_matrix().reshape(n, 9)  # scipy's, not fuzzkit's
    csv = tmp_path / "log.csv"
    write_log(
        csv,
        np.where(np.array(fpresent)[:, None], forces, math.nan),
        np.where(np.array(qpresent)[:, None], rot, math.nan),
    )
    outs = {}
    for name, source, extra in (
        ("bag", str(bag), ["--topic", "/ft/wrench", "--rotation-topic", "/tool/orientation"]),
        ("csv", str(csv), []),
    ):
        out = tmp_path / f"u_{name}.csv"
        code, _, err = run_cli(
            capsys, "replay", str(SPEC), "--forces", source, "--out", str(out), *extra
        )
        assert code == 0, err
        outs[name] = read_out(out)[1]
    bag_out, csv_out = outs["bag"], outs["csv"]
    np.testing.assert_array_equal(bag_out[:, 4], csv_out[:, 4])
    assert float(np.max(np.abs(bag_out[:, 1:4] - csv_out[:, 1:4]))) <= 1e-12
    assert np.ptp(csv_out[:, 3]) > 1e-4  # the controller did move: the comparison says something


def _good_bag(tmp_path: Path, storage: str = "sqlite3") -> Path:
    bag = tmp_path / "good"
    msgs = [
        (START_NS + k * PERIOD_NS, wrench(START_NS + k * PERIOD_NS, (0.0, 0.0, 1.0)))
        for k in range(5)
    ]
    write_bag(
        bag,
        storage,
        {
            "/ft/wrench": ("geometry_msgs/msg/WrenchStamped", msgs),
            "/tool/orientation": (
                "geometry_msgs/msg/QuaternionStamped",
                [(START_NS, quaternion(START_NS, (1.0, 0.0, 0.0, 0.0)))],
            ),
            "/empty": ("geometry_msgs/msg/WrenchStamped", []),
        },
    )
    return bag


FRAME = ["--frame-rotation", ",".join(repr(v) for v in DOWN)]


W = "geometry_msgs/msg/WrenchStamped"
Q = "geometry_msgs/msg/QuaternionStamped"
FT = ["--topic", "/ft/wrench"]


@pytest.mark.parametrize(
    "make, argv, message",
    [
        ("good", FRAME, f"choose the force topic with --topic NAME ({W} topics: /empty ({W}, "
         f"0 messages), /ft/wrench ({W}, 5 messages))"),
        ("good", ["--topic", "/ft/wrnch", *FRAME],
         "no topic '/ft/wrnch' in the bag (did you mean '/ft/wrench'?)"),
        ("good", ["--topic", "/tool/orientation", *FRAME],
         f"topic /tool/orientation holds {Q}, expected {W}"),
        ("good", ["--topic", "/empty", *FRAME], "topic /empty has no message"),
        ("good", [*FT, "--rotation-topic", "/ft/wrench"],
         f"topic /ft/wrench holds {W}, expected {Q} or"),
        ("good", FT, "needs the rotation columns r11,r12,...,r33, --rotation-topic or "
         "--frame-rotation"),
        ("good", [*FT, "--frame-rotation", "1,0,0,0,1,0,0,0"], "expected nine finite numbers"),
        ("good", [*FT, "--frame-rotation", "1,0,0,0,1,0,0,0,-1"], "is not a rotation"),
        ("good", [*FT, "--frame-rotation", "nan,0,0,0,1,0,0,0,1"], "expected nine finite"),
        ("good", [*FT, "--rotation-topic", "/tool/orientation", *FRAME],
         "give the tool rotation once"),
        ("garbage.db3", [*FT, *FRAME], "not a readable rosbag2 bag"),
        ("garbage.mcap", [*FT, *FRAME], "not a readable rosbag2 bag"),
        ("truncated.mcap", [*FT, *FRAME], "not a readable rosbag2 bag"),
        ("no_metadata", [*FT, *FRAME], "not a readable rosbag2 bag"),
        ("bad_message", [*FT, *FRAME], "the bag is damaged"),
        ("unset_stamp", [*FT, *FRAME], "is a header.stamp unset?"),
    ],
)  # fmt: skip
def test_malformed_bags_are_clear_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], make: str, argv: list[str], message: str
) -> None:
    if make == "good":
        source = _good_bag(tmp_path)
    elif make == "truncated.mcap":
        good = _good_bag(tmp_path, "mcap")
        (file,) = good.glob("*.mcap")
        source = tmp_path / "truncated.mcap"
        source.write_bytes(file.read_bytes()[: file.stat().st_size // 2])
    elif make == "no_metadata":
        source = tmp_path / "no_metadata"
        source.mkdir()
    elif make == "bad_message":
        source = tmp_path / "bad_message"
        with rosbag2.Writer(source, version=9) as writer:
            conn = writer.add_connection(
                "/ft/wrench", "geometry_msgs/msg/WrenchStamped", typestore=STORE
            )
            writer.write(conn, START_NS, b"\x00\x01\x00\x00\x07")  # a CDR header, then 1 byte
    elif make == "unset_stamp":
        source = tmp_path / "unset"
        msgs = [(1, wrench(0, (0.0, 0.0, 1.0))), (START_NS, wrench(START_NS, (0.0, 0.0, 1.0)))]
        write_bag(source, "sqlite3", {"/ft/wrench": ("geometry_msgs/msg/WrenchStamped", msgs)})
    else:
        source = tmp_path / make
        source.write_bytes(b"\x89not a bag at all\x00" * 50)
    out = tmp_path / "u.csv"
    code, _, err = run_cli(
        capsys, "replay", str(SPEC), "--forces", str(source), "--out", str(out), *argv
    )
    assert code == 2, err
    assert message in err, err
    assert err.count("error:") == 1 and ("damaged" in err) == (make == "bad_message"), err
    assert "Traceback" not in err and "internal error" not in err
    assert not out.exists()


def test_topic_options_on_a_csv_log_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv = tmp_path / "log.csv"
    csv.write_text("fx,fy,fz\n1,2,3\n")
    code, _, err = run_cli(
        capsys, "replay", str(SPEC_PI), "--forces", str(csv), "--out", str(tmp_path / "u.csv"),
        "--topic", "/ft",
    )  # fmt: skip
    assert code == 2 and "--topic and --rotation-topic read ROS 2 bags" in err


def test_a_frame_rotation_stands_for_the_rotation_columns_of_a_csv_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = load_spec(SPEC_PI)
    forces, _ = hostile_log(spec, n=80, seed=8)
    with_rot, without = tmp_path / "rot.csv", tmp_path / "plain.csv"
    write_log(with_rot, forces, np.tile(DOWN, (len(forces), 1)))
    write_log(without, forces, None)
    frame = ["--frame-rotation", ",".join(repr(v) for v in DOWN)]
    outs = []
    for log, extra in ((with_rot, []), (without, frame)):
        out = tmp_path / f"u_{log.stem}.csv"
        argv = ["replay", str(SPEC_PI), "--forces", str(log), "--out", str(out), *extra]
        assert run_cli(capsys, *argv)[0] == 0
        outs.append(read_out(out)[1])
    np.testing.assert_array_equal(outs[0], outs[1])
    # a log with its own rotation takes no fixed one
    argv = ["replay", str(SPEC_PI), "--forces", str(with_rot), "--out", str(tmp_path / "x.csv")]
    code, _, err = run_cli(capsys, *argv, *frame)
    assert code == 2 and "--frame-rotation is for logs without" in err
