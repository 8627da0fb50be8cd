"""The ``fuzzkit`` command.

Each group of subcommands lives in its own module with a ``register(subparsers)`` function;
handlers import their heavy dependencies lazily so ``fuzzkit --help`` stays fast. Any fuzzkit
error (all derive from ValueError or RuntimeError) is printed as ``fuzzkit: error: ...`` with a
non-zero exit code; no traceback reaches the user for bad input.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from fuzzkit.errors import FuzzkitError

#: Modules under fuzzkit.cli that contribute subcommands, in help order.
COMMAND_MODULES = (
    "rulebase",
    "codegen_cmd",
    "simulation",
    "tuning",
    "demo",
    "sweep",
)

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    from fuzzkit import __version__

    parser = argparse.ArgumentParser(
        prog="fuzzkit",
        description="Fuzzy-logic controller design kit: author, evaluate, compile, verify.",
    )
    parser.add_argument("--version", action="version", version=f"fuzzkit {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"fuzzkit.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"fuzzkit.cli.{name}":
                continue  # that command group is not built yet
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.handler(args)
    except FuzzkitError as exc:
        print(f"fuzzkit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (OSError, ValueError) as exc:
        print(f"fuzzkit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("fuzzkit: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug, not bad input: say so, traceback only on request
        if os.environ.get("FUZZKIT_DEBUG"):
            raise
        print(
            f"fuzzkit: internal error: {type(exc).__name__}: {exc}\n"
            "  this is a bug in fuzzkit; rerun with FUZZKIT_DEBUG=1 for the traceback",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    return int(code or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
