"""``fuzzkit plot``: the membership functions and rules of a rule base as one figure."""

from __future__ import annotations

import argparse
from typing import Any

from fuzzkit.cli import RULEBASE_SPEC_HELP
from fuzzkit.cli.units import store_alias

EXIT_OK = 0


def register(sub: Any) -> None:
    """Add the ``plot`` subcommand to the ``fuzzkit`` parser."""
    p = sub.add_parser(
        "plot",
        help="draw a rule base's membership functions and rules (PNG or SVG)",
        description="Draw the membership functions of every input and output (units on "
        "the axes) and the rules as one figure: a coloured grid for a rule table, numbered "
        "rules otherwise. The file is written whole or not at all.",
        epilog="examples:\n"
        "  fuzzkit plot macvicar_whelan --png macvicar_whelan.svg\n"
        "  fuzzkit plot my_controller.yaml --png my_controller.png",
    )
    p.add_argument("rulebase", metavar="RULEBASE", help=RULEBASE_SPEC_HELP)
    p.add_argument(
        "--png",
        dest="png",
        metavar="FILE.png|FILE.svg",
        help="figure to write, as --png of every command that draws one; the format follows "
        "the suffix (required)",
    )
    # the old spelling (plot's figure was its only output), kept working
    store_alias(p, "--out", "-o", dest="png", metavar="FILE")
    p.set_defaults(handler=cmd_plot)


def cmd_plot(args: argparse.Namespace) -> int:
    from fuzzkit.cli.file_kinds import require_rulebase
    from fuzzkit.errors import ConfigError
    from fuzzkit.fileio import check_output_path
    from fuzzkit.formats.registry import load
    from fuzzkit.viz.figures import figure_format
    from fuzzkit.viz.rulebase_plot import write_rulebase_plot

    if args.png is None:
        raise ConfigError("plot: give --png FILE.png (or FILE.svg), the figure to write")
    figure_format(args.png, "--png")
    check_output_path(args.png, "--png file")
    require_rulebase(args.rulebase, "plot")
    rb = load(args.rulebase)
    write_rulebase_plot(rb, args.png)
    print(f"wrote {args.png}")
    return EXIT_OK
