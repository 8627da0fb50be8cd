"""``fuzzkit import | export``: rule bases from and to MATLAB .fis, IEC 61131-7 FCL, fuzzylite FLL.

Every other command reads .fis/.fcl/.fll paths directly (by extension); these two convert
files, writing atomically so that a refused conversion leaves nothing behind.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

EXIT_OK = 0
#: ``--format`` choices: ``fuzzkit.formats.registry.EXPORT_FORMATS``, spelt here so that
#: building the parser imports no reader (a test holds the two equal).
FORMAT_NAMES = ("fis", "fcl", "fll")


def register(sub: Any) -> None:
    """Add the interop subcommands to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "import",
        help="convert a .fis, .fcl or .fll file to fuzzkit YAML",
        description="Read a MATLAB .fis, IEC 61131-7 .fcl (point lists or named shapes) or "
        "fuzzylite .fll file, check it like a YAML rule base, and write it as fuzzkit YAML. "
        "Constructs fuzzkit cannot express are refused with file:line:col, never approximated.",
        epilog="examples:\n"
        "  fuzzkit import tank.fis --out tank.yaml\n"
        "  fuzzkit import docs/examples/gripper_iec.fcl --out gripper.yaml",
    )
    p.add_argument("file", metavar="FILE", help="a .fis, .fcl or .fll file")
    p.add_argument("--out", required=True, metavar="RULEBASE.yaml", help="YAML file to write")
    p.set_defaults(handler=cmd_import)

    p = sub.add_parser(
        "export",
        help="write a rule base as .fis, .fcl or .fll",
        description="Write a rule base (a path in any supported format or a shipped name) as "
        "MATLAB .fis, FCL or fuzzylite FLL. What the format cannot express is refused, every "
        "item listed; what it would change (e.g. input clamping, which .fis and FCL lack) is "
        "refused unless --allow-loss is given.",
        epilog="examples:\n"
        "  fuzzkit export macvicar_whelan --format fll --out macvicar_whelan.fll\n"
        "  fuzzkit export my_controller.yaml --format fcl --dialect iec --out ctrl.fcl\n"
        "  fuzzkit export macvicar_whelan --format fis --allow-loss --out mw.fis",
    )
    p.add_argument("rulebase", metavar="RULEBASE", help="a rule-base path or a shipped name")
    p.add_argument(
        "--format",
        required=True,
        choices=FORMAT_NAMES,
        dest="fmt",
        help="MATLAB .fis, IEC 61131-7 FCL or fuzzylite FLL (required)",
    )
    p.add_argument(
        "--dialect",
        choices=("named", "iec"),
        default="named",
        help="FCL only: named shapes as fuzzylite and jFuzzyLogic read them (default) or "
        "IEC 61131-7 point lists",
    )
    p.add_argument(
        "--allow-loss",
        action="store_true",
        help="write even when the format changes the rule base's meaning somewhere (listed on "
        "stderr): outside the input ranges, or where no rule fires",
    )
    p.add_argument("--out", required=True, metavar="FILE", help="file to write")
    p.set_defaults(handler=cmd_export)


def _readable_size(text: str, out: str) -> str:
    """``text`` if fuzzkit's readers would read it back; else a ConfigError with the limit."""
    from fuzzkit.errors import ConfigError
    from fuzzkit.located_yaml import MAX_FILE_BYTES

    size = len(text.encode("utf-8"))
    if size > MAX_FILE_BYTES:
        raise ConfigError(
            f"{out}: not written: it would be {size} bytes, and rule-base files are limited to "
            f"{MAX_FILE_BYTES} bytes (1 MiB), so fuzzkit could not read it back"
        )
    return text


def cmd_import(args: argparse.Namespace) -> int:
    """Read FILE by extension, write it as YAML to --out."""
    from fuzzkit.errors import ConfigError
    from fuzzkit.fileio import check_output_path, write_atomic
    from fuzzkit.formats import fcl
    from fuzzkit.formats.registry import READERS, load
    from fuzzkit.formats.yaml_writer import dump

    suffix = Path(args.file).suffix.lower()
    if suffix not in READERS:
        *others, last = READERS
        expected = f"{', '.join(others)} or {last}"
        raise ConfigError(
            f"{args.file}: expected a {expected} file, got {suffix or 'no extension'!r}"
        )
    check_output_path(args.out, "YAML file")
    notes: dict[str, str] = {}
    if suffix == fcl.SUFFIX:  # FCL may leave ranges to be derived: say so in the YAML
        rb, _, notes = fcl.load_with_notes(args.file)
    else:
        rb = load(args.file)
    write_atomic(args.out, _readable_size(dump(rb, range_notes=notes), args.out))
    print(f"{args.file} -> {args.out} ({rb.name}: {len(rb.rules)} rules)")
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    """Write RULEBASE in --format to --out."""
    import sys

    from fuzzkit.fileio import check_output_path, write_atomic
    from fuzzkit.formats.foreign_common import ExportError
    from fuzzkit.formats.registry import FORMATS, dumps, load

    check_output_path(args.out, f".{args.fmt} file")
    rb = load(args.rulebase)
    fmt = FORMATS[args.fmt]
    lost = fmt.losses(rb)
    try:
        text = dumps(rb, args.fmt, allow_loss=args.allow_loss, dialect=args.dialect)
    except ExportError as exc:
        if lost and exc.items == tuple(lost):  # only losses: say the option, not the API
            raise ExportError(
                args.fmt,
                rb.name,
                lost,
                f"give --allow-loss to export anyway, with {fmt.meaning} meaning for these "
                "(each is then printed as a warning)",
            ) from None
        raise
    for item in lost:
        print(f"fuzzkit: warning: {args.out}: {item}", file=sys.stderr)
    write_atomic(args.out, _readable_size(text, args.out))
    print(f"{args.rulebase} -> {args.out}")
    return EXIT_OK
