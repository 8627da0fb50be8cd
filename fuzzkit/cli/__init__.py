"""The ``fuzzkit`` command.

Each group of subcommands lives in its own module with a ``register(subparsers)`` function;
handlers import their heavy dependencies lazily so ``fuzzkit --help`` stays fast. Any fuzzkit
error (all derive from ValueError or RuntimeError) is printed as ``fuzzkit: error: ...`` with a
non-zero exit code; no traceback reaches the user for bad input.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
from collections.abc import Sequence

from fuzzkit.errors import FuzzkitError
from fuzzkit.progress import interrupt_latch

#: Modules under fuzzkit.cli that contribute subcommands, in help order.
COMMAND_MODULES = (
    "rulebase",
    "plot",
    "interop",
    "codegen_cmd",
    "replay",
    "simulation",
    "tuning",
    "demo",
    "sweep",
)

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
#: 128 + SIGINT / SIGPIPE, as a shell reports a command ended by that signal.
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141
#: What a rule-base argument accepts (kept light: the CLI imports no format code to print help).
RULEBASE_SPEC_HELP = "a shipped name, or a rule-base file (.yaml, .yml, .fis, .fcl, .fll)"


def add_controller_impl_argument(parser: argparse.ArgumentParser) -> None:
    """``--controller-impl python|c``, the same for ``simulate``, ``sweep`` and ``tune``
    (``fuzzkit.studies.batch.CONTROLLER_IMPLS``)."""
    parser.add_argument(
        "--controller-impl",
        choices=("python", "c"),
        default="python",
        help="python (default): fuzzkit's own controller, the reference (in the compiled loop "
        "its numba twin); c: the run's controller spec (--spec, or built from the controller, "
        "gains, rule base and scenario) generated as C (double, the exact fuzzy surface) and "
        "run whole (front end, engagement, spike gate, trip and back-off, limits) inside the "
        "compiled loop; needs a C compiler",
    )


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Examples kept as written, descriptions wrapped, every default shown.

    Text with line breaks (the epilog's examples) is printed as written; a one-line
    description is wrapped to the terminal. An option's default is appended as
    ``(default: X)`` unless its help already says "default"; flags (``store_true``) and
    options without a default get nothing.
    """

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if "\n" in text:
            return super()._fill_text(text, width, indent)
        return argparse.HelpFormatter._fill_text(self, text, width, indent)

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        takes_value = action.nargs != 0
        if (
            takes_value
            and action.option_strings
            and default not in (None, argparse.SUPPRESS)
            and "default" not in text
        ):
            shown = " ".join(map(str, default)) if isinstance(default, list) else default
            text = f"{text} (default: {shown})" if text else f"default: {shown}"
        return text


def build_parser() -> argparse.ArgumentParser:
    from fuzzkit import __version__

    parser = argparse.ArgumentParser(
        prog="fuzzkit",
        description="Fuzzy-logic controller design kit: author, evaluate, compile, verify.",
        formatter_class=HelpFormatter,
        epilog="examples:\n"
        "  fuzzkit validate rulebases/*.yaml\n"
        "  fuzzkit compile macvicar_whelan --target c --out gen --verify\n"
        "  fuzzkit simulate E1 --controller fuzzy-pi --rrd e1.rrd\n"
        "  fuzzkit COMMAND --help     (every command's options, defaults and examples)",
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
    for command in sub.choices.values():
        command.formatter_class = HelpFormatter
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with interrupt_latch():
            code = args.handler(args)
        sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's exit
    except BrokenPipeError:
        # The reader went away (`fuzzkit validate ... | head`): stop quietly, as a command
        # killed by SIGPIPE would. Point stdout at devnull so the exit flush cannot fail
        # again (the recipe of the Python docs, "Note on SIGPIPE").
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return EXIT_BROKEN_PIPE
    except FuzzkitError as exc:
        print(f"fuzzkit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (OSError, ValueError) as exc:
        print(f"fuzzkit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # Every writer is atomic (fuzzkit.fileio), so whatever is on disk now is complete.
        print("fuzzkit: interrupted (Ctrl-C); nothing half-written", file=sys.stderr)
        return EXIT_INTERRUPTED
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


def console_main() -> None:
    """The ``fuzzkit`` console script and ``python -m fuzzkit``: :func:`main`, then exit.

    Once the command has finished, a late Ctrl-C has nothing left to stop: it is ignored
    rather than killing the interpreter while it shuts down (which would report a finished,
    fully written run as killed by SIGINT).

    An interrupted command has cleaned up on its way out (staging folders removed, worker
    pools shut down, every file written atomically or not at all), so the process ends there
    with :data:`EXIT_INTERRUPTED`, skipping the interpreter's shutdown. Under ``python -m``,
    CPython 3.11 turns any exit into a kill by SIGINT once a KeyboardInterrupt has left code
    run through its C API (``PyRun_String``), whatever exit code was asked for (seen with a
    Ctrl-C landing while scipy imports, inside a Cython module's init); and a Ctrl-C delivered
    at once inside numba's compiler (the second one) can leave LLVM memory that the shutdown's
    garbage collection would free twice.
    """
    code = main()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if code == EXIT_INTERRUPTED:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError):  # a closed pipe: nothing to say
                stream.flush()
        os._exit(EXIT_INTERRUPTED)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    console_main()
