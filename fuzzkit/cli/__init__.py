"""The ``fuzzkit`` command.

Each group of subcommands lives in its own module with a ``register(subparsers)`` function;
handlers import their heavy dependencies lazily so ``fuzzkit --help`` stays fast.

Errors are told apart by type, never by message: the user's errors (:data:`USER_ERRORS`: bad
input, a bad setting or environment, all of fuzzkit's own exception family rooted at
``fuzzkit.errors.FuzzkitError``, and an operating-system error such as a missing file) are
printed as ``fuzzkit: error: ...`` with exit 2. Anything else, a plain ``ValueError`` raised
deep inside a library included, is a bug in fuzzkit: ``fuzzkit: internal error: ...``, exit 1,
the traceback only with ``FUZZKIT_DEBUG=1``. A command module that fails to import is such a
bug too; no command silently drops out of ``--help``.
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

#: The exceptions that are the user's error (module docstring); every other one is a bug.
USER_ERRORS: tuple[type[Exception], ...] = (FuzzkitError, OSError)

#: Modules under fuzzkit.cli that contribute subcommands, in help order.
COMMAND_MODULES = (
    "rulebase",
    "plot",
    "interop",
    "codegen_cmd",
    "replay",
    "ros2_node",
    "simulation",
    "tuning",
    "demo",
    "sweep",
    "stability",
)

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
#: ``--fail-on-trip`` (simulate, compare, sweep): a run tripped the safety limit.
EXIT_TRIPPED = 3
#: 128 + SIGINT / SIGPIPE, as a shell reports a command ended by that signal.
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141
#: What a rule-base argument accepts (kept light: the CLI imports no format code to print help).
RULEBASE_SPEC_HELP = "a shipped name, or a rule-base file (.yaml, .yml, .fis, .fcl, .fll)"


def add_quiet_argument(parser: argparse.ArgumentParser, progress: bool = True) -> None:
    """``--quiet``, accepted by every command that runs studies, so that scripts can pass it
    alike; ``progress=False`` for the commands that draw no progress bar."""
    parser.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar"
        if progress
        else "accepted for scripts: this command draws no progress bar",
    )


def add_controller_impl_argument(parser: argparse.ArgumentParser) -> None:
    """``--controller-impl auto|c|python|reference``, the same for ``simulate``, ``sweep`` and
    ``tune`` (``fuzzkit.loop.spec.CONTROLLER_IMPLS``)."""
    from fuzzkit.loop.spec import CONTROLLER_IMPLS

    parser.add_argument(
        "--controller-impl",
        choices=CONTROLLER_IMPLS,
        default="auto",
        help="which code runs the run's controller spec (--spec, or built from the controller, "
        "gains, rule base and scenario): c, generated as C (double, the spec's surface), what "
        "`fuzzkit compile` ships, inside the compiled loop where the plant has one; python, "
        "the generated Python, in the Python loop; reference, fuzzkit's reference controller "
        "(for debugging), in the Python loop; auto (default): c where a C compiler exists, "
        "else python. The run's controller_impl says which ran",
    )


def add_plant_argument(parser: argparse.ArgumentParser, what: str, both: bool = False) -> None:
    """``--plant NAME``, its choices and help listing every plant of the registry
    (``fuzzkit.loop.adapter.PLANTS``), so that a new plant shows in every command; ``both``
    adds the report's ``both`` (planar and arm6)."""
    from fuzzkit.loop.adapter import PLANTS, plants_text

    parser.add_argument(
        "--plant",
        choices=[*sorted(PLANTS), *(["both"] if both else [])],
        default="planar",
        help=f"{what} (default: planar): {plants_text()}"
        + ("; both: planar and arm6" if both else ""),
    )


class CommandModuleError(RuntimeError):
    """A module of :data:`COMMAND_MODULES` failed to import (a bug, not the user's error)."""


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Examples kept as written, descriptions wrapped, every default shown.

    Text with line breaks (the epilog's examples) is printed as written; a one-line
    description is wrapped to the terminal. An option that takes a value shows its default:
    appended as ``(default: X)``, ``(default: none)`` for an option left out unless given, or
    ``(required)``, unless its help already says what the default is or that the option is
    required; flags (``store_true``) get nothing.
    """

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if "\n" in text:
            return super()._fill_text(text, width, indent)
        return argparse.HelpFormatter._fill_text(self, text, width, indent)

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        takes_value = action.nargs != 0
        if not (takes_value and action.option_strings) or text == argparse.SUPPRESS:
            return text
        if "default" in text.lower() or "required" in text.lower():
            return text  # the help says what the default means, or that there is none
        if action.required:
            shown = "required"
        elif default in (None, argparse.SUPPRESS):
            shown = "default: none"
        else:
            value = " ".join(map(str, default)) if isinstance(default, list) else default
            shown = f"default: {value}"
        return f"{text} ({shown})" if text else shown


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
        except Exception as exc:
            raise CommandModuleError(f"command module fuzzkit.cli.{name} failed to import") from exc
        module.register(sub)
    for command in sub.choices.values():
        command.formatter_class = HelpFormatter
    return parser


def _internal_error(exc: Exception) -> int:
    """Report ``exc`` as a bug in fuzzkit (re-raised with ``FUZZKIT_DEBUG`` set)."""
    if os.environ.get("FUZZKIT_DEBUG"):
        raise exc
    cause = f" ({type(exc.__cause__).__name__}: {exc.__cause__})" if exc.__cause__ else ""
    print(
        f"fuzzkit: internal error: {type(exc).__name__}: {exc}{cause}\n"
        "  this is a bug in fuzzkit; rerun with FUZZKIT_DEBUG=1 for the traceback",
        file=sys.stderr,
    )
    return EXIT_FAILURE


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code."""
    try:
        parser = build_parser()
    except CommandModuleError as exc:
        return _internal_error(exc)
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
    except USER_ERRORS as exc:
        print(f"fuzzkit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # Every writer is atomic (fuzzkit.fileio), so whatever is on disk now is complete.
        print("fuzzkit: interrupted (Ctrl-C); nothing half-written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # a bug, not bad input: say so, traceback only on request
        return _internal_error(exc)
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
