"""Seeded text mutations of rule-base and scenario files, for the fuzzing test.

Each mutant is one small edit of a valid file of the kind a hostile or damaged file holds: a
number replaced by an extreme one (huge, subnormal, NaN, a YAML 1.1 spelling), a line deleted,
duplicated or swapped, the file truncated, a control or structural character inserted, a
name replaced by a long or foreign one, a value replaced by another key of the format.
:func:`mutants` is deterministic for a seed, and each mutant says what was done so a failure
can be reproduced by hand.
"""

from __future__ import annotations

import random
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass

#: Numbers that have broken readers or the engine: too large for a float or for int(),
#: subnormal, non-finite, out of every sensible range, and YAML 1.1 integer spellings.
HOSTILE_NUMBERS = (
    "1" + "0" * 320,
    "1" + "0" * 5000,
    "1e309",
    "-1e309",
    "1e-320",
    "5e-324",
    "1e14",
    "-1e14",
    "1e18",
    "100000000",
    "1e-300",
    "1e300",
    "0",
    "-0",
    "nan",
    ".nan",
    "inf",
    ".inf",
    "-.inf",
    "0x1f",
    "0b11",
    "1_0",
    "1:30",
    "-1",
    "2",
    "0.5",
)
#: Characters whose insertion breaks structure in one of the formats.
STRUCTURE = ("[", "]", "{", "}", "(", ")", ":", ",", ";", "'", '"', "#", "=", "-", " ", "\n", "\t")
CONTROL = ("\x00", "\x01", "\x07", "\x1b", "\x7f", "\ufeff", "\u2028")
_NUMBER = re.compile(r"(?<![\w.])[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(?![\w.])")
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True, slots=True)
class Mutant:
    """A mutated text and how it was made (``what``) from which file (``origin``)."""

    origin: str
    what: str
    text: str


def _replace_number(text: str, rng: random.Random) -> tuple[str, str]:
    found = list(_NUMBER.finditer(text))
    if not found:
        return text, "no number"
    m = rng.choice(found)
    new = rng.choice(HOSTILE_NUMBERS)
    return text[: m.start()] + new + text[m.end() :], f"number {m.group()!r} -> {new[:12]!r}"


#: Lines whose numbers are structural: counts (``NumMFs=3``), ranges, durations, periods.
_KEY_LINE = re.compile(r"(?im)^.*(num\w+|range|duration|period|latency|samples|sensor:).*$")


def _replace_key_number(text: str, rng: random.Random) -> tuple[str, str]:
    """A number on a count, range or timing line replaced by a hostile one."""
    lines = [m for m in _KEY_LINE.finditer(text) if _NUMBER.search(m.group())]
    if not lines:
        return _replace_number(text, rng)
    line = rng.choice(lines)
    head, body, tail = text[: line.start()], line.group(), text[line.end() :]
    mutated, what = _replace_number(body, rng)
    return head + mutated + tail, f"{what} on line {text.count(chr(10), 0, line.start()) + 1}"


def _lines(text: str) -> list[str]:
    return text.split("\n")


def _delete_line(text: str, rng: random.Random) -> tuple[str, str]:
    lines = _lines(text)
    k = rng.randrange(len(lines))
    return "\n".join(lines[:k] + lines[k + 1 :]), f"line {k + 1} deleted"


def _duplicate_line(text: str, rng: random.Random) -> tuple[str, str]:
    lines = _lines(text)
    k = rng.randrange(len(lines))
    return "\n".join(lines[: k + 1] + lines[k:]), f"line {k + 1} duplicated"


def _swap_lines(text: str, rng: random.Random) -> tuple[str, str]:
    lines = _lines(text)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return "\n".join(lines), f"lines {i + 1} and {j + 1} swapped"


def _truncate(text: str, rng: random.Random) -> tuple[str, str]:
    if rng.random() < 0.5:  # just after a token that promises more (":=", ":", "=", "(")
        cuts = [m.end() for m in re.finditer(r":=|:|=|\(|\[|\{", text)]
        k = rng.choice(cuts) if cuts else rng.randrange(len(text))
    else:
        k = rng.randrange(len(text))
    return text[:k], f"truncated after {k} characters"


def _insert(text: str, rng: random.Random, pool: tuple[str, ...], kind: str) -> tuple[str, str]:
    k = rng.randrange(len(text) + 1)
    ch = rng.choice(pool)
    return text[:k] + ch + text[k:], f"{kind} {ch!r} inserted at {k}"


def _delete_span(text: str, rng: random.Random) -> tuple[str, str]:
    k = rng.randrange(len(text))
    n = rng.randint(1, 12)
    return text[:k] + text[k + n :], f"{n} characters deleted at {k}"


def _replace_word(text: str, rng: random.Random) -> tuple[str, str]:
    found = list(_WORD.finditer(text))
    if not found:
        return text, "no word"
    m = rng.choice(found)
    options = [w.group() for w in found] + ["x" * 300, "yes", "on", "null", "if", "and", "NaN"]
    new = rng.choice(options)
    return text[: m.start()] + new + text[m.end() :], f"word {m.group()!r} -> {new[:12]!r}"


#: ``key: value`` in YAML (and ``key = value`` / ``key := value`` in the foreign formats).
_KEY_VALUE = re.compile(r"([A-Za-z_]\w*)\s*(?::=|:|=)[ \t]*'?([A-Za-z_]\w*)")


def keyword_values(text: str) -> tuple[list[re.Match[str]], list[str]]:
    """Where ``text`` gives a key a word as value, and the keys it uses (in order, once)."""
    found = list(_KEY_VALUE.finditer(text))
    return found, list(dict.fromkeys(m.group(1) for m in found))


def replace_value(text: str, m: re.Match[str], new: str) -> str:
    """``text`` with the value of the ``key: value`` match ``m`` replaced by ``new``."""
    return text[: m.start(2)] + new + text[m.end(2) :]


def _keyword_as_value(text: str, rng: random.Random) -> tuple[str, str]:
    """A value (``shape: triangle``) replaced by another key of the file (``shape: rules``)."""
    found, keys = keyword_values(text)
    if not found:
        return _replace_word(text, rng)
    m, new = rng.choice(found), rng.choice(keys)
    return replace_value(text, m, new), f"value {m.group(2)!r} of {m.group(1)!r} -> {new!r}"


_OPERATORS: tuple[Callable[[str, random.Random], tuple[str, str]], ...] = (
    _replace_number,
    _replace_number,
    _replace_key_number,
    _replace_key_number,
    _delete_line,
    _duplicate_line,
    _swap_lines,
    _truncate,
    lambda t, r: _insert(t, r, STRUCTURE, "structure character"),
    lambda t, r: _insert(t, r, CONTROL, "control character"),
    _delete_span,
    _replace_word,
    _replace_word,
    _keyword_as_value,
)


def mutants(sources: dict[str, str], count: int, seed: int) -> Iterator[Mutant]:
    """``count`` mutants of the texts in ``sources`` ({origin: text}), round robin, seeded.

    About one in four mutants carries two edits, so that damage meets damage.
    """
    rng = random.Random(seed)
    origins = sorted(sources)
    for i in range(count):
        origin = origins[i % len(origins)]
        text = sources[origin]
        steps = []
        for _ in range(2 if rng.random() < 0.25 else 1):
            text, what = rng.choice(_OPERATORS)(text, rng)
            steps.append(what)
        yield Mutant(origin, "; ".join(steps), text)
