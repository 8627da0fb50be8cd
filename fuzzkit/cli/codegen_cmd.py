"""``fuzzkit compile``: a rule base to C or Python (lookup table or exact inference), verified.

Everything is computed and checked before anything is written; the output folder then gets
all files at once (``write_tree_atomic``) or none.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from fuzzkit.cli import RULEBASE_SPEC_HELP, numbers
from fuzzkit.control.names import GAIN_KEYS

EXIT_OK = 0
EXIT_FAILURE = 1

#: What the generated table fuzzy-PI takes (``fuzzkit.codegen.emit.FPI_GAIN_KEYS``, which may
#: not import fuzzkit.control; kept here so the parser does not import fuzzkit.codegen): the
#: fuzzy-PI's scaling factors and the correction limits, not the step limit.
FPI_GAIN_KEYS = (*GAIN_KEYS["fuzzy-pi"], "u_min", "u_max")


def register(sub: Any) -> None:
    """Add ``compile`` to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "compile",
        help="compile a rule base (lookup table or exact inference) or a whole controller "
        "spec to C or Python (a controller spec also to an FMU)",
        description="Generate C (NAME.h, NAME.c) or Python (NAME.py) for a rule base, either "
        "as a lookup table sampled from the exact engine with a verified error bound "
        "(--method table) or as the exact inference itself, rounding error only "
        "(--method exact). --method auto (default) takes the table when one meets the "
        "tolerance within --max-bytes and the exact method otherwise, and says why. "
        "--verify compiles/imports the result and compares it with the exact engine on 1e5 "
        "random points and the edge cases. "
        "Given a controller spec (a YAML file with axes/controller keys) it generates the "
        "whole outer-loop controller instead: NAME_controller.{h,c} (plus NAME_surface.{h,c}, "
        "a fuzzy-PI's rule base by the exact method) or NAME_controller.py, --type float "
        "(default for C) or double; --verify then runs it on a hostile sensor log against "
        "fuzzkit's reference controller. --target fmu (controller specs only) writes "
        "--out NAME.fmu, an FMI 2.0 Co-Simulation FMU of the controller (double): "
        "modelDescription.xml, the C sources and the Linux x86-64 binary (docs/fmu.md).",
        epilog="examples:\n"
        "  fuzzkit compile macvicar_whelan --target c --out gen --verify\n"
        "  fuzzkit compile macvicar_whelan --target c --method exact --out gen_exact --verify\n"
        "  fuzzkit compile macvicar_whelan --target c --type q15 --tolerance 2e-3 --out gen_q15\n"
        "  fuzzkit compile my_controller.yaml --target python --resolution 65 --out gen_py\n"
        "  fuzzkit compile docs/examples/controller.yaml --target c --type double --out fw "
        "--verify\n"
        "  fuzzkit compile docs/examples/controller.yaml --target fmu --out e1_fuzzy.fmu",
    )
    p.add_argument(
        "rulebase", metavar="RULEBASE|SPEC", help=RULEBASE_SPEC_HELP + ", or a controller spec"
    )
    p.add_argument("--target", required=True, help="c, python or fmu (required)")
    p.add_argument(
        "--type",
        dest="number_type",
        default=None,
        help="C number type: float (default; double for a controller spec whose surface is a "
        "table), double or q15; python always computes in double",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--tolerance",
        type=numbers.TOLERANCE,
        default=None,
        metavar="T",
        help="allowed error as a fraction of each output range (default 1e-3)",
    )
    size.add_argument(
        "--resolution",
        type=numbers.BREAKPOINTS,
        default=None,
        metavar="N",
        help="breakpoints per input instead of a tolerance search",
    )
    p.add_argument(
        "--method",
        default="auto",
        help="auto (default), table or exact",
    )
    p.add_argument(
        "--max-bytes",
        type=numbers.TABLE_BYTES,
        default=None,
        metavar="B",
        help="auto: largest table (constant data bytes) to take before the exact method "
        "(default 8192)",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    p.add_argument(
        "--verify",
        action="store_true",
        help="compile (C) or import (Python) the result and check it against the exact engine",
    )
    p.add_argument(
        "--gains",
        metavar="GAINS.yaml",
        default=None,
        help="bake fuzzy-PI gains (kp, ki, kx, u_min, u_max) in as defaults",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_compile)


def _fpi_defaults(path: str | None) -> Any:
    from fuzzkit.codegen.emit import FpiDefaults
    from fuzzkit.control.gains import read_gains
    from fuzzkit.errors import ConfigError

    if path is None:
        return None
    gains = read_gains(path, "fuzzy-pi", required=True)
    # The generated controller implements exactly these; dropping another key (rate_limit)
    # would ship a controller that behaves unlike the one simulated with the same file.
    unsupported = [k for k in gains if k not in FPI_GAIN_KEYS]
    if unsupported:
        raise ConfigError(
            f"{path}: the generated fuzzy-PI does not implement {', '.join(unsupported)} "
            f"(it takes {', '.join(FPI_GAIN_KEYS)}); remove it from the file given to --gains"
        )
    missing = [k for k in FPI_GAIN_KEYS if k not in gains]
    if missing:
        raise ConfigError(
            f"{path}: compile --gains needs all of {', '.join(FPI_GAIN_KEYS)} for fuzzy-pi "
            f"(missing: {', '.join(missing)})"
        )
    values = {k: float(gains[k]) for k in FPI_GAIN_KEYS}
    bad = [k for k, v in values.items() if not math.isfinite(v)]
    if bad:
        raise ConfigError(f"{path}: gains must be finite numbers (got {bad[0]}={values[bad[0]]})")
    return FpiDefaults(**values, source=path)


def method_sentence(method: str, reason: str) -> str:
    """What ``fuzzkit compile`` chose and why, in one plain sentence."""
    what = {
        "table": "a lookup table (error within the verified bound above)",
        "exact": "the exact inference, no table (rounding error only)",
    }.get(method, method)
    return f"{what}, because {reason}."


def cmd_compile(args: argparse.Namespace) -> int:
    """Handler of ``fuzzkit compile``."""
    from pathlib import Path

    from fuzzkit.cli.file_kinds import is_kind

    if is_kind(args.rulebase, "controller spec"):
        from fuzzkit.cli.controller_compile import compile_spec

        return compile_spec(args)

    from fuzzkit.codegen.lookup_table import NUMBER_TYPES
    from fuzzkit.codegen.method import DEFAULT_MAX_BYTES, compile_rulebase
    from fuzzkit.codegen.provenance import refuse_overwrite
    from fuzzkit.codegen.target import all_targets, load_target
    from fuzzkit.errors import CodegenError, ConfigError
    from fuzzkit.fileio import write_tree_atomic
    from fuzzkit.formats.registry import load
    from fuzzkit.progress import TaskBars

    # Cheap checks first, so a typo costs nothing and nothing is written.
    target = load_target(args.target)
    if not {"table", "exact"} & set(target.files):
        raise CodegenError(
            f"the {target.name} target makes whole controllers only: give it a controller "
            f"spec (a YAML file with axes/controller keys), not the rule base {args.rulebase}"
        )
    number_type = args.number_type or target.default_number_type
    if number_type not in NUMBER_TYPES:
        raise CodegenError(
            f"unknown --type {number_type!r} (expected one of {', '.join(NUMBER_TYPES)})"
        )
    if number_type not in target.number_types:
        others = [t.label for t in all_targets() if number_type in t.number_types]
        raise CodegenError(
            f"--type {number_type} applies to the {' and '.join(others)} target; the "
            f"{target.name} target computes in {' or '.join(target.number_types)}"
        )
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a directory (expected an output folder)")
    defaults = _fpi_defaults(args.gains)

    max_bytes = DEFAULT_MAX_BYTES if args.max_bytes is None else args.max_bytes

    rb = load(args.rulebase)
    with TaskBars(f"{rb.name}: ", quiet=args.quiet, unit="pt") as bars:
        result = compile_rulebase(
            rb,
            args.target,
            number_type,
            method=args.method,
            tolerance=args.tolerance,
            resolution=args.resolution,
            max_bytes=max_bytes,
            fpi_defaults=defaults,
            progress=bars,
        )
    files = result.files
    table = result.table
    refuse_overwrite(out, files)
    if table is not None:
        print(f"{rb.name}: {table.describe()}")
    else:
        print(f"{rb.name}: exact inference ({number_type}), rounding error only")
    print(f"method: {method_sentence(result.method, result.reason)}")
    for line in result.warnings:
        print(line)
    if len(rb.inputs) != 2:
        print(f"note: no fuzzy-PI API (it needs 2 inputs, {rb.name} has {len(rb.inputs)})")
    if defaults is not None and len(rb.inputs) != 2:
        print("note: --gains ignored (no fuzzy-PI API)")
    if args.verify:
        with TaskBars(f"{rb.name}: ", quiet=args.quiet, unit="pt") as bars:
            if table is None:
                result_v = target.verify_exact(rb, number_type, files, progress=bars)
            else:
                result_v = target.verify_table(rb, table, files, progress=bars)
        print(result_v.describe())
        if not result_v.ok:
            print("nothing written: the generated code does not match the exact engine")
            return EXIT_FAILURE
    written = write_tree_atomic(out, files)
    for path in written:
        print(f"wrote {path}")
    return EXIT_OK
