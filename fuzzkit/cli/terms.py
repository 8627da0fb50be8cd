"""``fuzzkit terms``: draw a rule base's membership functions (MATLAB's ``plotmf``)."""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0


def register(sub: Any) -> None:
    """Add the ``terms`` subcommand to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "terms",
        help="draw every variable's membership functions to a PNG",
        description="Draw the terms of every input and output of a rule base (any supported "
        "format, or a shipped name), one panel per variable, the range shaded.",
    )
    p.add_argument("rulebase", metavar="RULEBASE", help="a rule-base path or a shipped name")
    p.add_argument("--png", required=True, metavar="OUT.png", help="PNG image to write")
    p.set_defaults(handler=cmd_terms)


def cmd_terms(args: argparse.Namespace) -> int:
    """Load RULEBASE and write its membership functions to --png."""
    from fuzzkit.fileio import check_output_path
    from fuzzkit.formats.registry import load
    from fuzzkit.viz.terms import write_terms_png

    check_output_path(args.png, "PNG file")
    rb = load(args.rulebase)
    write_terms_png(rb, args.png)
    print(f"wrote {args.png}")
    return EXIT_OK
