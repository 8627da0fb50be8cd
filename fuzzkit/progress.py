"""Progress bars for long commands (tune, report, compile), drawn by tqdm, and the Ctrl-C latch
they check.

A bar is drawn only on a terminal and when the user did not ask for ``--quiet``: piped or
logged stderr stays free of carriage returns. Library code never draws one itself; it takes a
callback, and the command line passes one made here.

Ctrl-C: Python turns SIGINT into a KeyboardInterrupt wherever the interpreter happens to be,
and one raised inside a finaliser or a C callback (``__del__``, a weakref callback, a ctypes
callback: numba and llvmlite run many while they load or compile a kernel) is printed as
"Exception ignored ..." with a traceback and dropped, so the command would carry on as if
nothing happened. :func:`interrupt_latch` remembers the signal as well, keeps such a dropped
KeyboardInterrupt off stderr (the latch has it), and every progress update (bars drawn or
silent) raises it again: a long command stops at its next step.

Some work must not be cut in the middle: a KeyboardInterrupt raised inside numba's compiler
(LLVM objects half handed over from one owner to another) corrupts memory, and the process dies
later with a double free. Inside :func:`interrupt_shield` (``fuzzkit.jit`` enters one for
every numba compile and cache load) the first Ctrl-C is held, with a note on stderr, and
delivered as soon as the shielded work ends; a second Ctrl-C is delivered at once.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType
from typing import IO, Any

_interrupted = threading.Event()
#: Depth of :func:`interrupt_shield` blocks entered by the main thread, and whether a Ctrl-C
#: is being held until the outermost one ends.
_shield = {"depth": 0, "held": False}
HELD_NOTE = "fuzzkit: Ctrl-C: stopping when the compile in progress ends (Ctrl-C again: now)"


def _on_sigint(signum: int, frame: FrameType | None) -> None:
    _interrupted.set()
    if _shield["depth"] > 0 and not _shield["held"]:
        _shield["held"] = True
        with contextlib.suppress(OSError, ValueError):  # stderr closed: hold it all the same
            print(HELD_NOTE, file=sys.stderr, flush=True)
        return
    _shield["held"] = False
    raise KeyboardInterrupt


def enter_interrupt_shield() -> None:
    """Start work that a KeyboardInterrupt must not cut (see :func:`interrupt_shield`).

    Other threads' calls count for nothing: only the main thread receives Ctrl-C."""
    if threading.current_thread() is threading.main_thread():
        _shield["depth"] += 1


def leave_interrupt_shield() -> None:
    """End the work of the matching :func:`enter_interrupt_shield`; leaving the outermost
    one delivers a held Ctrl-C (SIGINT is raised again, so the handler of the moment runs)."""
    if threading.current_thread() is not threading.main_thread() or _shield["depth"] == 0:
        return
    _shield["depth"] -= 1
    if _shield["depth"] == 0 and _shield["held"]:
        _shield["held"] = False
        signal.raise_signal(signal.SIGINT)


@contextmanager
def interrupt_shield() -> Iterator[None]:
    """Within the block the first Ctrl-C is held until the block ends (a second one is
    delivered at once); nested blocks hold it until the outermost ends."""
    enter_interrupt_shield()
    try:
        yield
    finally:
        leave_interrupt_shield()


@contextmanager
def interrupt_latch() -> Iterator[None]:
    """Within the block, SIGINT raises KeyboardInterrupt *and* is remembered for
    :func:`raise_if_interrupted`; the previous handler comes back afterwards. Outside the main
    thread (where no handler can be installed) it does nothing."""
    _interrupted.clear()
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, _on_sigint)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _quiet_dropped_interrupt(previous_hook)
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        signal.signal(signal.SIGINT, previous)
        _interrupted.clear()
        _shield["held"] = False


def _quiet_dropped_interrupt(hook: Any) -> Any:
    """An ``sys.unraisablehook`` that passes everything to ``hook`` except a KeyboardInterrupt
    raised by the latch's own handler, which the latch re-raises at the next progress update."""

    def unraisable(info: Any) -> None:
        if isinstance(info.exc_value, KeyboardInterrupt) and _interrupted.is_set():
            return
        hook(info)

    return unraisable


def raise_if_interrupted() -> None:
    """Raise KeyboardInterrupt if Ctrl-C came during the current :func:`interrupt_latch`, even
    when the first KeyboardInterrupt was lost in a finaliser."""
    if _interrupted.is_set():
        raise KeyboardInterrupt


def progress_wanted(stream: IO[str] | None, quiet: bool = False) -> bool:
    """Whether to draw progress on ``stream``: not ``quiet`` and ``stream`` is a terminal."""
    if quiet or stream is None:
        return False
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty()) if callable(isatty) else False
    except (ValueError, OSError):  # a closed stream
        return False


def progress_bar(
    total: float | None,
    desc: str,
    *,
    stream: IO[str] | None = None,
    quiet: bool = False,
    unit: str = "it",
    leave: bool = True,
    unit_scale: bool = False,
) -> Any:
    """A tqdm bar (with elapsed time and ETA) on ``stream`` (default stderr).

    It is a disabled, silent bar unless :func:`progress_wanted`; callers update it the same
    way either way. ``unit_scale`` writes large counts as 36.1k. Use it as a context manager
    so the line is ended (or the bar closed) on an error or Ctrl-C too.
    """
    out = sys.stderr if stream is None else stream
    return _latched_tqdm()(
        total=total,
        desc=desc,
        unit=unit,
        file=out,
        disable=not progress_wanted(out, quiet),
        dynamic_ncols=True,
        unit_scale=unit_scale,
        leave=leave,
    )


class TaskBars:
    """A ``progress(task, done, total)`` callback drawing one bar per task, in turn.

    For work that reports in several stages of unknown number (the table search of
    ``fuzzkit.codegen.table_search``): a new task name closes the previous bar and opens
    the next; the bars vanish when done. Use as a context manager so the last bar is closed.
    """

    def __init__(
        self, prefix: str, *, stream: IO[str] | None = None, quiet: bool = False, unit: str = "it"
    ) -> None:
        self.prefix = prefix
        self.stream = stream
        self.quiet = quiet
        self.unit = unit
        self.task: str | None = None
        self.bar: Any = None

    def __call__(self, task: str, done: int, total: int) -> None:
        """Show that ``done`` of ``total`` units of ``task`` are finished."""
        if task != self.task or self.bar is None:
            self.close()
            self.task = task
            self.bar = progress_bar(
                total,
                f"{self.prefix}{task}",
                stream=self.stream,
                quiet=self.quiet,
                unit=self.unit,
                leave=False,
                unit_scale=True,
            )
        if total != self.bar.total:
            self.bar.total = total
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """Close the current bar, if any."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> TaskBars:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _latched_tqdm() -> Any:
    """tqdm whose every update first checks the Ctrl-C latch (tqdm is imported on first use)."""
    global _LATCHED
    if _LATCHED is None:
        from tqdm import tqdm

        class LatchedTqdm(tqdm):  # type: ignore[misc]
            def update(self, n: float | None = 1) -> bool | None:
                raise_if_interrupted()
                return super().update(n)  # type: ignore[no-any-return]

        _LATCHED = LatchedTqdm
    return _LATCHED


_LATCHED: Any = None
