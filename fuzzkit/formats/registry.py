"""Find rule bases by shipped name or by path: the entry point most users call.

A path is read by its extension: ``.yaml``/``.yml`` (fuzzkit's format), ``.fis`` (MATLAB),
``.fcl`` (IEC 61131-7, both dialects) or ``.fll`` (fuzzylite), so every command that takes a
rule base takes any of them.

Shipped rule bases live in the package ``fuzzkit.rulebases`` (the repository's ``rulebases/``
folder) and are read with :mod:`importlib.resources`, so names resolve the same way from a
source checkout, an editable install and a plain ``pip install .``.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from fuzzkit.errors import Location, Problem, RuleBaseError, did_you_mean
from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.foreign_common import ExportError, ForeignFormat
from fuzzkit.formats.yaml_reader import load_file_with_warnings, loads_rulebase_with_warnings
from fuzzkit.fuzzy import validation
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.fuzzy.type2_model import footprint_of

_PACKAGE = "fuzzkit.rulebases"
#: fuzzkit's own format: YAML.
YAML_SUFFIXES = (".yaml", ".yml")
#: Every foreign format, by name: each module's ``FORMAT`` record (reader, writer, suffix,
#: first word, losses). Adding a format is its module and one entry here.
FORMATS: dict[str, ForeignFormat] = {f.name: f for f in (fis.FORMAT, fcl.FORMAT, fll.FORMAT)}
#: Foreign formats: extension -> reader of a path, returning the rule base and its warnings.
READERS = {f.suffix: f.read for f in FORMATS.values()}
#: Foreign formats: the names :func:`dumps` takes.
EXPORT_FORMATS = tuple(FORMATS)
#: Every extension read as a rule base, in help order.
RULEBASE_SUFFIXES = (*YAML_SUFFIXES, *READERS)


def dumps(rb: RuleBase, fmt: str, *, allow_loss: bool = False, dialect: str = "named") -> str:
    """``rb`` as the text of foreign format ``fmt`` (``fis``, ``fcl`` or ``fll``).

    Raises
    ------
    ExportError
        The format cannot hold part of ``rb`` (each part listed); see each module's
        ``refusals`` and ``losses``.
    ValueError
        Unknown format or FCL dialect.
    """
    too_deep = validation.depth_problems(rb)
    if too_deep:  # the readers refuse these; the writers must not produce them
        raise RuleBaseError(validation.as_problems(rb, too_deep))
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; expected one of {', '.join(EXPORT_FORMATS)}")
    if footprint_of(rb) is not None:
        # a writer of type-1 terms would drop every lower membership function, even with
        # allow_loss: the result would be another controller
        raise ExportError(
            fmt,
            rb.name,
            ["interval type-2 terms (upper/lower functions) and the type reduction"],
            "fuzzkit writes interval type-2 rule bases as YAML only (docs/type2.md)",
        )
    return FORMATS[fmt].write(rb, allow_loss, dialect)


def _or(items: tuple[str, ...]) -> str:
    """``a, b or c``."""
    return f"{', '.join(items[:-1])} or {items[-1]}" if len(items) > 1 else items[0]


def _load_path(path: str | os.PathLike[str]) -> tuple[RuleBase, list[Problem]]:
    p = Path(path)
    reader = READERS.get(p.suffix.lower())
    return reader(p) if reader is not None else load_file_with_warnings(p)


def available() -> list[str]:
    """Names of the shipped rule bases, sorted (``load(name)`` accepts each)."""
    root = resources.files(_PACKAGE)
    return sorted(
        entry.name.rsplit(".", 1)[0]
        for entry in root.iterdir()
        if entry.is_file() and entry.name.endswith(YAML_SUFFIXES)
    )


def looks_like_path(spec: str) -> bool:
    """True when ``spec`` names a file (a rule-base extension or a path separator), not a
    shipped rule base."""
    return (
        spec.lower().endswith(RULEBASE_SUFFIXES)
        or os.sep in spec
        or "/" in spec
        or (os.altsep is not None and os.altsep in spec)
    )


def load(name_or_path: str | os.PathLike[str]) -> RuleBase:
    """Load a rule base from a file path or by the name of a shipped rule base.

    A string ending in ``.yaml``/``.yml``/``.fis``/``.fcl``/``.fll`` or containing a path
    separator is a path, read by its extension (YAML when it has none of the foreign ones);
    any other string is a shipped name (see :func:`available`).

    Raises
    ------
    RuleBaseError
        The file is malformed (every problem listed), missing, or the name is unknown.

    Examples
    --------
    >>> rb = load("macvicar_whelan")
    >>> rb.input_names
    ('e', 'de')
    """
    return load_with_warnings(name_or_path)[0]


def load_with_warnings(name_or_path: str | os.PathLike[str]) -> tuple[RuleBase, list[Problem]]:
    """:func:`load`, also returning the warnings (coverage gaps under ``coverage: allow_gaps``).

    Each warning is a :class:`~fuzzkit.errors.Problem` with severity ``warning``, located at
    ``file:line:col``. ``fuzzkit validate`` prints them (``--strict`` makes them errors).
    """
    if isinstance(name_or_path, os.PathLike):
        return _load_path(Path(name_or_path))
    spec = str(name_or_path)
    if looks_like_path(spec):
        return _load_path(spec)
    names = available()
    if spec not in names:
        if Path(spec).exists():  # a file (or a folder, which load_file reports) right here
            return _load_path(spec)
        raise RuleBaseError(
            [
                Problem(
                    Location(spec),
                    f"no shipped rule base or file called {spec!r}{did_you_mean(spec, names)}; "
                    f"shipped: {', '.join(names)} "
                    f"(or give a path to a {_or((YAML_SUFFIXES[0], *READERS))} "
                    "file)",
                )
            ]
        )
    resource = resources.files(_PACKAGE).joinpath(spec + ".yaml")
    if not resource.is_file():
        resource = resources.files(_PACKAGE).joinpath(spec + ".yml")
    text = resource.read_text(encoding="utf-8")
    return loads_rulebase_with_warnings(text, source=f"<shipped>/{resource.name}")


def loads(text: str, source: str = "<string>") -> RuleBase:
    """Parse rule-base YAML from a string; ``source`` names it in error messages."""
    return loads_rulebase_with_warnings(text, source)[0]
