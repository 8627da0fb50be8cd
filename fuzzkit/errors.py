"""Exception types of fuzzkit.

Every error a user can provoke derives from a built-in (``ValueError`` for bad input,
``RuntimeError`` for a failure of the machinery) so callers can catch it without importing
fuzzkit, and every error about a file names the place as ``file:line:col``.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass


def did_you_mean(word: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'X'?)`` for the closest candidate, or an empty string."""
    pool = list(candidates)
    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.5)
    if not close:
        # Labels differ in case often enough ('pl' for 'PL') to try a case-insensitive match.
        lowered = {c.lower(): c for c in pool}
        if word.lower() in lowered:
            close = [lowered[word.lower()]]
    return f" (did you mean {close[0]!r}?)" if close else ""


@dataclass(frozen=True, slots=True)
class Location:
    """A place in a source file; ``line`` and ``col`` are 1-based, 0 when unknown."""

    file: str
    line: int = 0
    col: int = 0

    def __str__(self) -> str:
        if self.line <= 0:
            return self.file
        if self.col <= 0:
            return f"{self.file}:{self.line}"
        return f"{self.file}:{self.line}:{self.col}"


@dataclass(frozen=True, slots=True)
class Problem:
    """One thing wrong with an input, with where it is.

    ``severity`` is ``"error"`` (the input cannot be used) or ``"warning"`` (it can, but
    something deserves a look, e.g. a coverage gap); warnings print with a ``warning:`` prefix.
    """

    location: Location
    message: str
    severity: str = "error"

    def __str__(self) -> str:
        if self.severity == "warning":
            return f"{self.location}: warning: {self.message}"
        return f"{self.location}: {self.message}"


class FuzzkitError(Exception):
    """Base of every fuzzkit exception (always combined with a built-in base)."""


class ProblemsError(FuzzkitError, ValueError):
    """Bad input with one or more located problems, all listed in the message."""

    def __init__(self, problems: Iterable[Problem], summary: str = "") -> None:
        self.problems: tuple[Problem, ...] = tuple(problems)
        if not self.problems:
            raise RuntimeError("ProblemsError needs at least one problem")
        lines = [str(p) for p in self.problems]
        head = summary or (f"{len(lines)} problem{'s' if len(lines) != 1 else ''} found")
        super().__init__(head + ":\n" + "\n".join(lines) if len(lines) > 1 else lines[0])


class RuleBaseError(ProblemsError):
    """A rule base (YAML or Python-built) is malformed; every problem is listed."""


class EvaluationError(FuzzkitError, ValueError):
    """Inputs handed to an engine do not fit the rule base (unknown or missing names, shapes)."""


class CodegenError(FuzzkitError, ValueError):
    """A rule base cannot be compiled as asked (tolerance unreachable, bad target or type)."""


class ToolchainError(FuzzkitError, RuntimeError):
    """The system C compiler or loader failed on generated code."""


class SimulationError(FuzzkitError, RuntimeError):
    """A closed-loop simulation could not proceed (unreachable target, unstable plant)."""


class ConfigError(FuzzkitError, ValueError):
    """A configuration file (gains, robot description, experiment options) is malformed."""


class ConfigFileError(ProblemsError, ConfigError):
    """A configuration file (gains, robot description) is malformed; every problem located."""


class ScenarioError(ProblemsError):
    """A scenario file is malformed; every problem is listed as ``file:line:col``."""


class ControllerSpecError(ProblemsError):
    """A controller spec file is malformed; every problem is listed as ``file:line:col``."""
