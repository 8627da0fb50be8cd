"""``fuzzkit replay``: a controller spec run on a recorded sensor log (reference or generated C)."""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0


def register(sub: Any) -> None:
    """Add ``replay`` to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "replay",
        help="run a controller spec on a recorded wrist-sensor log (CSV)",
        description="Run the controller of a spec on a sensor log, sample by sample from reset, "
        "and write the correction and status of every row. The log is CSV with a header: "
        "fx,fy,fz (N, task frame) required; t (s) and the tool rotation r11,r12,...,r33 "
        "(row-major, world-from-sensor; needed when the spec compensates gravity) optional. An "
        "empty cell or nan is a missing sample. The output has [t,]ux,uy,uz (m),status. "
        "--impl python is fuzzkit's reference controller, --impl c the generated C, compiled "
        "and run: replay both and compare to check the generated controller on your robot's "
        "log. A run's CSV (fuzzkit simulate --csv) is read as it is: the sample the controller "
        "received, and the run's corrections, which the replay is compared with (the largest "
        "difference is printed).",
        epilog="examples:\n"
        "  fuzzkit replay docs/examples/controller.yaml --forces log.csv --out u_ref.csv\n"
        "  fuzzkit replay docs/examples/controller.yaml --forces log.csv --out u_c.csv --impl c\n"
        "  fuzzkit simulate E1 --spec SPEC --csv run.csv && "
        "fuzzkit replay SPEC --forces run.csv --out u.csv --impl c",
    )
    p.add_argument("spec", metavar="SPEC", help="controller spec (YAML)")
    p.add_argument("--forces", required=True, metavar="LOG.csv", help="the sensor log")
    p.add_argument(
        "--out", required=True, metavar="OUT.csv", help="output CSV (written atomically)"
    )
    p.add_argument(
        "--impl",
        default="python",
        choices=("python", "c"),
        help="python: the reference controller; c: the generated C (needs a C compiler)",
    )
    p.add_argument(
        "--type",
        dest="number_type",
        default="double",
        choices=("double", "float"),
        help="number type of the generated C (--impl c)",
    )
    p.set_defaults(handler=cmd_replay)


def cmd_replay(args: argparse.Namespace) -> int:
    """Handler of ``fuzzkit replay``."""
    import numpy as np

    from fuzzkit.control import status as st
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.errors import Location, Problem, ProblemsError
    from fuzzkit.fileio import check_output_path, write_atomic
    from fuzzkit.studies.replay import read_sensor_log, replay, replay_csv

    check_output_path(args.out)
    spec = load_spec(args.spec)
    log = read_sensor_log(args.forces)
    if spec.sensor.tool is not None and log.rotations is None:
        raise ProblemsError(
            [
                Problem(
                    Location(args.forces, 1, 1),
                    f"the spec {spec.name!r} compensates the tool's weight (sensor.tool): the "
                    "log needs the rotation columns r11,r12,...,r33",
                )
            ]
        )
    out, status = replay(spec, log, args.impl, args.number_type)
    write_atomic(args.out, replay_csv(log, out, status))
    n = len(status)
    counts = ", ".join(
        f"{name} {int(np.count_nonzero(status & bit))}" for name, bit in st.BITS.items()
    )
    impl = "reference (python)" if args.impl == "python" else f"generated C ({args.number_type})"
    print(f"{spec.name}: {n} samples replayed by the {impl} controller; rows with {counts}")
    if log.recorded is not None:
        worst = float(np.max(np.abs(out - log.recorded))) if n else 0.0
        print(f"largest difference from the run's corrections (u<a>_m): {worst:.3g} m")
    print(f"wrote {args.out}")
    return EXIT_OK
