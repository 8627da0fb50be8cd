"""The progress callback the long computations of code generation report to.

``progress(task, done, total)``: ``done`` of ``total`` points (``total`` may grow) of the work
``task`` names are evaluated: each table the search builds (``table_search``), each
``--verify`` check (``verify``). A caller draws it (``fuzzkit compile`` draws a bar,
``fuzzkit.progress.TaskBars``, and its Ctrl-C latch acts at each report); codegen never prints.
"""

from __future__ import annotations

from collections.abc import Callable

ProgressFn = Callable[[str, int, int], None]

__all__ = ["ProgressFn"]
