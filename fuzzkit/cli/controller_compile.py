"""``fuzzkit compile SPEC``: the whole outer-loop controller of a spec as C, Python or an FMU.

Everything is generated (and, with ``--verify``, compiled or imported and run against the
reference controller) before anything is written; the output folder then gets every file at
once or none (a one-file target such as the FMU: the file is written atomically).
"""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1
#: 1e-9 m: the double build must equal the reference to this, per sample.
DOUBLE_TOLERANCE_M = 1e-9


def _refuse_rulebase_options(args: argparse.Namespace) -> None:
    from fuzzkit.errors import CodegenError

    given = [
        flag
        for flag, value in (
            ("--tolerance", args.tolerance),
            ("--resolution", args.resolution),
            ("--max-bytes", args.max_bytes),
            ("--gains", args.gains),
        )
        if value is not None
    ]
    if args.method not in ("auto", "exact"):
        given.append(f"--method {args.method}")
    if given:
        raise CodegenError(
            f"{args.rulebase}: {', '.join(given)} applies to rule bases; a controller spec's "
            "gains are in the spec, and so is how its fuzzy-PI surface is evaluated "
            "(surface: exact, or {method: table, tolerance: T} or {method: table, resolution: N})"
        )


def default_number_type(spec: Any, target_default: str) -> str:
    """The number type without ``--type``: double for a table surface (its lookup table is
    stored and interpolated in double, as the closed loop runs it), else the target's."""
    return "double" if spec.surface.method == "table" else target_default


def compile_spec(args: argparse.Namespace) -> int:
    """Generate, optionally verify, then write the controller of the spec ``args.rulebase``."""
    from pathlib import Path

    import numpy as np

    from fuzzkit.codegen.controller import float_step_bound
    from fuzzkit.codegen.provenance import refuse_overwrite
    from fuzzkit.codegen.target import load_target
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.errors import ConfigError
    from fuzzkit.fileio import write_atomic, write_tree_atomic
    from fuzzkit.loop.controller_code import design_of, generate
    from fuzzkit.studies.replay import SensorLog, replay
    from fuzzkit.studies.sensor_logs import hostile_log

    _refuse_rulebase_options(args)
    target = load_target(args.target)
    out = Path(args.out)
    if target.bundle is None and out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a directory (expected an output folder)")
    if target.bundle is not None and out.is_dir():
        raise ConfigError(f"{out}: is a directory (the {target.name} target writes one file)")
    spec = load_spec(args.rulebase)
    number_type = args.number_type or default_number_type(spec, target.default_number_type)
    files = generate(spec, target.name, number_type)
    if target.bundle is None:
        refuse_overwrite(out, files)
    print(f"{spec.name}: {spec.kind} controller, {target.label} ({number_type})")
    if args.verify:
        if target.open_controller is None:  # pragma: no cover - both shipped targets can
            raise ConfigError(f"the {target.name} target cannot run a controller to verify it")
        forces, rotations = hostile_log(spec)
        ctl = target.open_controller(files, f"{spec.name}_controller", number_type)
        got, status = ctl.run(forces, rotations)
        want, want_status = replay(spec, SensorLog(forces, rotations, None), "python")
        err = np.abs(got - want).max(axis=1)
        if number_type == "double":
            allowed = np.full(len(err), DOUBLE_TOLERANCE_M)
        else:
            step = float_step_bound(design_of(spec), 1000.0)
            allowed = step * np.arange(1, len(err) + 1)
        mismatched = int(np.count_nonzero(status != want_status))
        ok = bool(np.all(err <= allowed)) and mismatched == 0
        verdict = "ok" if ok else "FAILED"
        print(
            f"verify: {verdict} on a hostile log of {len(err)} samples against the reference "
            f"controller (largest |u - u_ref| {err.max():.3g} m, {mismatched} status mismatches)"
        )
        if not ok:
            print("nothing written: the generated controller does not match the reference")
            return EXIT_FAILURE
    if target.bundle is not None:
        print(f"wrote {write_atomic(out, target.bundle(files, spec.name))}")
        return EXIT_OK
    for path in write_tree_atomic(out, files):
        print(f"wrote {path}")
    return EXIT_OK
