"""Golden files of generated code and how they are compared (not a test module).

Generated text is compared with the checked-in files under tests/golden/ exactly, but for
floating-point literals, which are compared by value (:func:`golden_difference`);
``FUZZKIT_REFRESH_GOLDEN=1`` rewrites the files (:func:`check_golden`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from fuzzkit.fuzzy.model import RuleBase

GOLDEN = Path(__file__).parent / "golden"
REFRESH = os.environ.get("FUZZKIT_REFRESH_GOLDEN") == "1"

#: Floating-point literals in generated tables come from numpy/scipy sums whose rounding changes
#: between releases; they are compared by value, each relative to its own magnitude, within
#: this many units in the last place of the target's number type (issue 29 item 5: a 1e-4
#: relative change in any constant fails, a gain of 1e-4 m included). Only literals that are
#: rounding noise of a sum near 0 are compared absolutely, against :data:`NOISE_FLOOR` times
#: the output's full scale (:func:`full_scale`): that is double rounding, whatever the type.
#: Q15 codes are integers and compared exactly, like every other part of the text.
ULPS = {"double": 64, "float": 2, "q15": 0}
_EPS = {"double": float(np.finfo(np.float64).eps), "float": float(np.finfo(np.float32).eps)}
NOISE_FLOOR = 64 * _EPS["double"]
FLOAT_LITERAL = re.compile(
    r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+(?=[eE]))(?:[eE][-+]?\d+)?(?:f\b)?"
)


_LIST_SEPARATOR = re.compile(r"\s*,\s*")


def _split_literals(text: str) -> tuple[list[str], list[float]]:
    # a list of literals wrapped at another place (a literal printed longer or shorter) is the
    # same list: separators that are a comma and white space compare as ", "
    parts = [", " if _LIST_SEPARATOR.fullmatch(p) else p for p in FLOAT_LITERAL.split(text)]
    values = [float(m.rstrip("f")) for m in FLOAT_LITERAL.findall(text)]
    return parts, values


def check_golden(folder: Path, files: dict[str, str], number_type: str, scale: float) -> None:
    """``files`` equal the golden files in ``folder`` (``FUZZKIT_REFRESH_GOLDEN=1`` rewrites
    them): the same names, text equal but for float literals within ``ULPS`` of themselves
    (or within the rounding noise of ``scale``, the output's full scale, :func:`full_scale`)."""
    if REFRESH:
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.iterdir():
            old.unlink()
        for rel, text in files.items():
            (folder / rel).write_text(text, encoding="utf-8")
    expected = {p.name: p.read_text(encoding="utf-8") for p in sorted(folder.iterdir())}
    assert sorted(expected) == sorted(files), "set FUZZKIT_REFRESH_GOLDEN=1 to rewrite"
    for rel, text in files.items():
        problem = golden_difference(text, expected[rel], ULPS[number_type], number_type, scale)
        assert problem is None, f"{folder / rel}: {problem}; FUZZKIT_REFRESH_GOLDEN=1 rewrites it"


def full_scale(rb: RuleBase) -> float:
    """The largest magnitude of the rule base's output ranges: the floor of a literal's
    tolerance (a file's largest literal may be a placeholder such as 1e30 or 1e200)."""
    return max(max(abs(v.low), abs(v.high)) for v in rb.outputs)


def golden_difference(got: str, want: str, ulps: int, number_type: str, scale: float) -> str | None:
    """Why ``got`` differs from the golden ``want``, or None if it matches.

    Everything outside floating-point literals must be identical; each literal must be within
    ``ulps`` units in the last place of the target type of itself, or within
    :data:`NOISE_FLOOR` times ``scale`` (the output's full scale, :func:`full_scale`) if that
    is larger: noise of a sum near 0 (Q15: exact text).
    """
    if number_type == "q15" or ulps == 0:
        return None if got == want else "text differs"
    got_parts, got_values = _split_literals(got)
    want_parts, want_values = _split_literals(want)
    if got_parts != want_parts or len(got_values) != len(want_values):
        for k, (a, b) in enumerate(zip(got.splitlines(), want.splitlines(), strict=False)):
            if FLOAT_LITERAL.sub("#", a) != FLOAT_LITERAL.sub("#", b):
                return f"text differs at line {k + 1}: {a!r} != {b!r}"
        return "text differs (line count)"
    eps = _EPS[number_type]
    for a, b in zip(got_values, want_values, strict=True):
        tol = max(ulps * eps * max(abs(a), abs(b)), NOISE_FLOOR * scale)
        if not abs(a - b) <= tol:
            return f"literal {a!r} differs from golden {b!r} by more than {ulps} ulps ({tol:.3g})"
    return None
