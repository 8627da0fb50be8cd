"""Running the docs' commands as the test does: through the shell where the shell is part of
the command, else in the test's own process, isolated so that it behaves as a fresh one.

In-process runs call :func:`fuzzkit.cli.main`, the function behind the ``fuzzkit`` console
script (``fuzzkit.cli:console_main`` in pyproject.toml, which only adds the process's exit):
the command's argv, in its scratch folder, with stdout and stderr captured and its exit code
(a ``SystemExit`` included) returned. What one command could leave behind for the next is put
back or cleared around each: the working folder, the environment, ``sys.argv``, the SIGINT
handler, warning filters (a fresh interpreter's, not pytest's), the logging setup,
matplotlib's backend (Agg), figures and settings, and fuzzkit's functools caches (some are
keyed by a file's path, so a second command would see the first one's file). fuzzkit's
dict caches are keyed by content (a model's identity, generated code's sha256) and stay.
The process itself is the subject of ``tests/test_cli_process.py`` (``python -m fuzzkit``,
signals, closed pipes).
"""

from __future__ import annotations

import contextlib
import functools
import io
import logging
import os
import signal
import subprocess
import sys
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from tests._doc_plan import Group, Step, words

#: Characters that make a command the shell's: globs, pipes, redirections, lists, expansions.
SHELL_CHARACTERS = frozenset("*?[]|&;<>$`(){}~")


@dataclass(frozen=True)
class Outcome:
    """What a command did: its exit code and what it printed."""

    code: int
    stdout: str
    stderr: str


def needs_shell(command: str) -> bool:
    """Whether ``command`` has a shell character outside quotes (the shell must run it)."""
    quote = ""
    for ch in command:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in SHELL_CHARACTERS:
            return True
    return False


def run(command: str, folder: Path, opened: list[str] | None = None) -> Outcome:
    """Run ``command`` (a ``fuzzkit`` command line) in ``folder``, as :func:`needs_shell`
    says; run in-process, the files it opens for reading are appended to ``opened``."""
    if needs_shell(command):
        return run_in_shell(command, folder)
    argv = words(command)
    if argv[0] != "fuzzkit":
        raise ValueError(f"not a fuzzkit command: {command}")
    return run_in_process(argv[1:], folder, opened)


def run_in_shell(command: str, folder: Path) -> Outcome:
    """``command`` through ``sh``, with this interpreter's ``fuzzkit`` first on PATH."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    res = subprocess.run(
        command, shell=True, cwd=folder, env=env, capture_output=True, text=True, timeout=600
    )
    return Outcome(res.returncode, res.stdout, res.stderr)


class _Opened:
    """The files this process opens for reading while :attr:`paths` is a list (an audit
    hook: it cannot be removed, so it is installed once and does nothing between runs)."""

    paths: list[str] | None = None
    installed = False

    @classmethod
    def hook(cls, event: str, args: tuple[object, ...]) -> None:
        if event != "open" or cls.paths is None:
            return
        path, mode, flags = args
        reading = (
            not any(ch in mode for ch in "wax+")
            if isinstance(mode, str)
            else isinstance(flags, int) and flags & os.O_ACCMODE == os.O_RDONLY
        )
        if reading and isinstance(path, str | os.PathLike):
            cls.paths.append(os.path.abspath(path))

    @classmethod
    @contextlib.contextmanager
    def recording(cls) -> Iterator[list[str]]:
        if not cls.installed:
            sys.addaudithook(cls.hook)
            cls.installed = True
        cls.paths = paths = []
        try:
            yield paths
        finally:
            cls.paths = None


def run_in_process(argv: list[str], folder: Path, opened: list[str] | None = None) -> Outcome:
    """``fuzzkit ARGV`` in this process, in ``folder``, isolated (module docstring); the
    files it opens for reading are appended to ``opened``."""
    from fuzzkit.cli import main

    out = io.TextIOWrapper(io.BytesIO(), encoding="utf-8", write_through=True)
    err = io.TextIOWrapper(io.BytesIO(), encoding="utf-8", write_through=True)
    with contextlib.ExitStack() as stack:
        stack.enter_context(_as_a_fresh_process(argv, folder))
        stack.enter_context(contextlib.redirect_stdout(out))
        stack.enter_context(contextlib.redirect_stderr(err))
        paths = stack.enter_context(_Opened.recording())
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors and --help
            code = _exit_code(exc, err)
    if opened is not None:
        opened.extend(paths)
    return Outcome(code, _text(out), _text(err))


def _exit_code(exc: SystemExit, err: io.TextIOWrapper) -> int:
    """The code a process ending with ``exc`` exits with (a message is printed, code 1)."""
    if exc.code is None or isinstance(exc.code, int):
        return exc.code or 0
    print(exc.code, file=err)
    return 1


def _text(stream: io.TextIOWrapper) -> str:
    buffer = stream.buffer
    assert isinstance(buffer, io.BytesIO)
    return buffer.getvalue().decode("utf-8", errors="replace")


@contextlib.contextmanager
def _as_a_fresh_process(argv: list[str], folder: Path) -> Iterator[None]:
    """Within the block, the process's state is a fresh ``fuzzkit`` process's, as far as a
    command can tell; afterwards it is the test's again."""
    environ, cwd, sys_argv = dict(os.environ), os.getcwd(), sys.argv
    sigint = signal.getsignal(signal.SIGINT)
    root = logging.getLogger()
    handlers, level, disabled = root.handlers[:], root.level, logging.root.manager.disable
    os.environ["MPLBACKEND"] = "Agg"
    sys.argv = ["fuzzkit", *argv]
    clear_fuzzkit_caches()
    mpl_settings = _matplotlib_settings()
    os.chdir(folder)
    try:
        with warnings.catch_warnings():
            _fresh_warning_filters()
            yield
    finally:
        os.chdir(cwd)
        _close_figures(mpl_settings)
        os.environ.clear()
        os.environ.update(environ)
        sys.argv = sys_argv
        signal.signal(signal.SIGINT, sigint)
        root.handlers[:] = handlers
        root.setLevel(level)
        logging.disable(disabled)


def clear_fuzzkit_caches() -> int:
    """Clear every functools cache of fuzzkit's loaded modules; return how many there were."""
    n = 0
    for name, module in list(sys.modules.items()):
        if module is None or not (name == "fuzzkit" or name.startswith("fuzzkit.")):
            continue
        for value in list(vars(module).values()):
            if isinstance(value, functools._lru_cache_wrapper):
                value.cache_clear()
                n += 1
    return n


def _fresh_warning_filters() -> None:
    """The filters of an interpreter started without ``-W`` (the Python docs, "Default
    Warning Filter"): pytest's own filters would turn some warnings into errors."""
    warnings.resetwarnings()
    warnings.filterwarnings("default", category=DeprecationWarning, module="__main__")
    for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning):
        warnings.filterwarnings("ignore", category=category, append=True)
    warnings.filterwarnings("ignore", category=ResourceWarning, append=True)


def _matplotlib_settings() -> dict[str, object] | None:
    """matplotlib's settings before the command (None when it is not imported yet: the
    command imports it with ``MPLBACKEND=Agg``); then its backend Agg and its settings those
    of its rc file, as a fresh process has them."""
    mpl = sys.modules.get("matplotlib")
    if mpl is None:
        return None
    saved = dict(mpl.rcParams)
    mpl.use("Agg")
    mpl.rc_file_defaults()
    return saved


def _close_figures(saved: dict[str, object] | None) -> None:
    """Close the figures the command left open and put matplotlib's settings back."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close("all")
    mpl = sys.modules.get("matplotlib")
    if mpl is not None and saved is not None:
        dict.update(mpl.rcParams, saved)  # as matplotlib's rc_context restores them


# --------------------------------------------------------------------------- a group


def _files(folder: Path) -> dict[PurePosixPath, tuple[int, int]]:
    """Every file under ``folder`` with its (modification time, size)."""
    out = {}
    for path in folder.rglob("*"):
        if path.is_file():
            st = path.stat()
            out[PurePosixPath(path.relative_to(folder).as_posix())] = (st.st_mtime_ns, st.st_size)
    return out


def _undeclared(
    step: Step, before: dict[PurePosixPath, tuple[int, int]], folder: Path
) -> list[str]:
    """The files ``step`` wrote or changed that none of its output paths names: the plan
    (``tests/_doc_plan.py``) would not know a later command depends on them."""
    after = _files(folder)
    changed = [p for p, stamp in after.items() if before.get(p) != stamp]
    outputs = step.outputs
    return [str(p) for p in changed if not any(p == o or o in p.parents for o in outputs)]


def _unnamed_reads(step: Step, opened: list[str], folder: Path) -> list[str]:
    """The files ``step`` opened that an earlier command of its page writes and it does not
    name: a dependency the plan does not see (it would run without that command before it)."""
    inside = {
        PurePosixPath(Path(p).relative_to(folder).as_posix())
        for p in opened
        if Path(p).is_relative_to(folder)
    }
    return sorted(str(p) for p in inside if any(p == u or u in p.parents for u in step.unnamed))


def run_group(group: Group, folder: Path) -> list[str]:
    """Run the group's commands in order in ``folder`` (a workspace); return one message per
    failure, naming every ``page:line`` that shows the command."""
    failures = []
    folder = folder.resolve()
    for step in group.steps:
        before = _files(folder)
        opened: list[str] = []
        outcome = run(step.text, folder, opened)
        if outcome.code != 0:
            failures.append(
                f"{step.where}: {step.text}\nexit {outcome.code}\n"
                f"{outcome.stdout[-2000:]}{outcome.stderr[-3000:]}"
            )
        stray = _undeclared(step, before, folder)
        if stray:
            failures.append(
                f"{step.where}: {step.text}\nwrote {', '.join(stray)}, which none of its "
                "output options names (tests/_doc_plan.py OUTPUT_OPTIONS)"
            )
        hidden = _unnamed_reads(step, opened, folder)
        if hidden:
            failures.append(
                f"{step.where}: {step.text}\nread {', '.join(hidden)}, which an earlier "
                "command of its page writes, without naming it (tests/_doc_plan.py)"
            )
    return failures
