"""``fuzzkit replay``: a controller spec run on a recorded sensor log (CSV or a ROS 2 bag) by
the reference or a generated controller, or by all three to compare them."""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1


def register(sub: Any) -> None:
    """Add ``replay`` to the ``fuzzkit`` parser."""
    from fuzzkit.loop.spec import CONTROLLER_IMPLS

    p = sub.add_parser(
        "replay",
        help="run a controller spec on a recorded wrist-sensor log (CSV or ROS 2 bag)",
        description="Run the controller of a spec on a sensor log, sample by sample from reset, "
        "and write the correction and status of every row. The log is CSV with a header: "
        "fx,fy,fz (N, task frame) required; t (s) and the tool rotation r11,r12,...,r33 "
        "(row-major, world-from-sensor; needed when the spec compensates gravity) optional. An "
        "empty cell or nan is a missing sample. Or the log is a ROS 2 bag (a rosbag2 folder, "
        "or its .db3 or .mcap file) with a geometry_msgs/msg/WrenchStamped topic (--topic), "
        "resampled to the spec's period by the messages' stamps: the last message is held, "
        "and a period with no new message is a missing sample. The output has "
        "[t,]ux,uy,uz (m),status. --impl names the controller as simulate's "
        "--controller-impl does: the spec's generated controller (c, compiled and run; python, "
        "the generated module imported; auto, c where a compiler exists, else python), or "
        "reference, fuzzkit's reference controller; --compare runs the reference and both "
        "generated ones and prints the largest difference per column. A run's CSV "
        "(fuzzkit simulate --csv) is read as it is: the sample the controller received, and the "
        "run's corrections and status bits, which the replay is compared with: it reproduces "
        "the run when every status is equal and the corrections are within 1e-12 of their "
        "largest magnitude (exit 1 when not).",
        epilog="examples:\n"
        "  fuzzkit replay docs/examples/controller.yaml --forces log.csv --out u.csv\n"
        "  fuzzkit replay docs/examples/controller.yaml --forces log.csv --out u_ref.csv "
        "--impl reference\n"
        "  fuzzkit replay docs/examples/controller.yaml --forces log.csv --compare\n"
        "  fuzzkit replay docs/examples/controller_pi.yaml --forces bag/ --topic /ft --out u.csv\n"
        "  fuzzkit simulate E1 --spec SPEC --csv run.csv && "
        "fuzzkit replay SPEC --forces run.csv --out u.csv --impl c",
    )
    p.add_argument("spec", metavar="SPEC", help="controller spec (YAML)")
    p.add_argument(
        "--forces",
        required=True,
        metavar="LOG",
        help="the sensor log: CSV, or a ROS 2 bag (folder, .db3 or .mcap)",
    )
    p.add_argument(
        "--out",
        metavar="OUT.csv",
        default=None,
        help="output CSV, written atomically (default: none; required unless --compare, "
        "which writes the reference's output there when given)",
    )
    p.add_argument(
        "--impl",
        default="auto",
        choices=CONTROLLER_IMPLS,
        help="which code runs the spec, as simulate's --controller-impl: c, the generated C "
        "(needs a C compiler); python, the generated Python module; auto (default): c where a "
        "C compiler exists, else python; reference, fuzzkit's reference controller (for "
        "debugging, and --schedule)",
    )
    p.add_argument(
        "--compare",
        action="store_true",
        help="replay through all three implementations and print, per column, the largest "
        "difference of each generated one from the reference (default: off)",
    )
    p.add_argument(
        "--type",
        dest="number_type",
        default="double",
        choices=("double", "float"),
        help="number type of the generated C (--impl c, --compare) (default: double)",
    )
    p.add_argument(
        "--status",
        dest="status_format",
        default="bits",
        choices=("bits", "names"),
        help="the output's status column: bits (default), the integer bit mask; names, the set "
        "bits' names joined by | (ENGAGED|SATURATED; 0 when none)",
    )
    p.add_argument(
        "--schedule",
        default=None,
        metavar="CHANGES.csv",
        help="parameter changes during the replay (--impl reference only): CSV period,name,value, "
        "names as the FMU's tunable parameters (kp_z, ki_z, kx_z, setpoint_z, limit_n) and the "
        "events tare and reset (value 1) (default: none)",
    )
    p.add_argument(
        "--topic",
        default=None,
        metavar="NAME",
        help="bag logs: the WrenchStamped topic (default: none; when omitted the bag's wrench "
        "topics are listed)",
    )
    p.add_argument(
        "--rotation-topic",
        default=None,
        metavar="NAME",
        help="bag logs: a QuaternionStamped, PoseStamped or TransformStamped topic with the "
        "tool rotation, world-from-sensor (default: none)",
    )
    p.add_argument(
        "--frame-rotation",
        default=None,
        metavar="R11,...,R33",
        help="a fixed tool rotation, nine numbers row-major world-from-sensor, for a log "
        "without one (default: none)",
    )
    p.set_defaults(handler=cmd_replay)


def _read_log(args: argparse.Namespace, period_s: float) -> Any:
    """The log of ``--forces`` (CSV or bag), with ``--frame-rotation`` applied."""
    import numpy as np

    from fuzzkit.errors import ConfigError
    from fuzzkit.studies.replay import SensorLog, read_sensor_log
    from fuzzkit.studies.rosbag_log import is_bag, parse_frame_rotation, read_bag_log

    fixed = None if args.frame_rotation is None else parse_frame_rotation(args.frame_rotation)
    if args.rotation_topic is not None and fixed is not None:
        raise ConfigError("give the tool rotation once: --rotation-topic or --frame-rotation")
    if is_bag(args.forces):
        return read_bag_log(args.forces, period_s, args.topic, args.rotation_topic, fixed)
    if args.topic is not None or args.rotation_topic is not None:
        raise ConfigError(
            f"{args.forces}: --topic and --rotation-topic read ROS 2 bags (a folder, .db3 or "
            ".mcap); this log is CSV"
        )
    log = read_sensor_log(args.forces)
    if fixed is None:
        return log
    if log.rotations is not None:
        raise ConfigError(
            f"{args.forces}: the log has rotation columns; --frame-rotation is for logs without"
        )
    rot = np.tile(np.asarray(fixed, dtype=np.float64), (log.forces.shape[0], 1))
    return SensorLog(log.forces, rot, log.times)


def cmd_replay(args: argparse.Namespace) -> int:
    """Handler of ``fuzzkit replay``."""
    import numpy as np

    from fuzzkit.control import status as st
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.errors import ConfigError, Location, Problem, ProblemsError
    from fuzzkit.fileio import check_output_path, write_atomic
    from fuzzkit.studies.replay import compare, replay_csv, replayed_by, reproduction
    from fuzzkit.studies.rosbag_log import is_bag

    if args.out is None and not args.compare:
        raise ConfigError("replay needs --out OUT.csv (or --compare, which prints a table)")
    if args.out is not None:
        check_output_path(args.out)
    spec = load_spec(args.spec)
    log = _read_log(args, spec.period_s)
    if spec.sensor.tool is not None and log.rotations is None:
        raise ProblemsError(
            [
                Problem(
                    Location(args.forces) if is_bag(args.forces) else Location(args.forces, 1, 1),
                    f"the spec {spec.name!r} compensates the tool's weight (sensor.tool): the "
                    "log needs the rotation columns r11,r12,...,r33, --rotation-topic or "
                    "--frame-rotation",
                )
            ]
        )
    n = log.forces.shape[0]
    schedule = []
    if args.schedule is not None:
        from fuzzkit.studies.param_schedule import read_schedule

        if args.compare:
            raise ConfigError(
                "--schedule changes the reference only (--impl reference): not with --compare"
            )
        schedule = read_schedule(args.schedule, spec, n)
    if args.compare:
        (out, status), diffs = compare(spec, log, args.number_type)
        print(
            f"{spec.name}: {n} samples replayed by the reference (python), the generated "
            f"Python and the generated C ({args.number_type})"
        )
        _print_differences(diffs, args.number_type)
    else:
        out, status, ran = replayed_by(spec, log, args.impl, args.number_type, schedule)
        counts = ", ".join(
            f"{name} {int(np.count_nonzero(status & bit))}" for name, bit in st.BITS.items()
        )
        print(
            f"{spec.name}: {n} samples replayed by the {_label(ran, args.number_type)} "
            f"controller; rows with {counts}"
        )
    verdict = reproduction(out, status, log)
    for line in verdict.lines() if verdict is not None else ():
        print(line)
    if args.out is not None:
        write_atomic(args.out, replay_csv(log.times, out, status, args.status_format == "names"))
        print(f"wrote {args.out}")
    return EXIT_OK if verdict is None or verdict.ok else EXIT_FAILURE


def _label(impl: str, number_type: str) -> str:
    """What ``impl`` (``c``, ``python``, ``reference``) is, as replay prints it."""
    from fuzzkit.studies.replay import IMPL_LABELS

    return IMPL_LABELS[impl] + (f" ({number_type})" if impl == "c" else "")


def _print_differences(diffs: Any, number_type: str) -> None:
    """The largest difference from the reference per column, one column per implementation."""
    heads = ["column", *(_label(d.impl, number_type) for d in diffs)]
    rows = [
        [f"u{axis} (m)", *(f"{d.largest_m[i]:.3g}" for d in diffs)] for i, axis in enumerate("xyz")
    ]
    rows.append(["status (rows differing)", *(str(d.status_rows) for d in diffs)])
    widths = [max(len(r[i]) for r in [heads, *rows]) for i in range(len(heads))]
    print("largest difference from the reference:")
    for r in [heads, *rows]:
        print("  " + "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip())
