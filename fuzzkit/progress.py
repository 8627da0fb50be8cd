"""Progress bars for long commands (tune, report, compile), drawn by tqdm.

A bar is drawn only on a terminal and when the user did not ask for ``--quiet``: piped or
logged stderr stays free of carriage returns. Library code never draws one itself; it takes a
callback, and the command line passes one made here.
"""

from __future__ import annotations

import sys
from typing import IO, Any


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
    from tqdm import tqdm

    out = sys.stderr if stream is None else stream
    return tqdm(
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
