"""Which rule base or controller spec a generated file came from, read from its first line.

Every generated file's first line names its source in double quotes: ``fuzzy controller
"NAME"`` for a rule base (and a spec's surface, which is compiled as the rule base
``SPEC_surface``), ``force-loop controller "NAME"`` for a controller spec. ``fuzzkit compile``
reads it from the files it would replace, and refuses to overwrite another source's files
(issue 40 item 7): two rule bases never share a file name (``codegen.names``), but a folder
can hold files of an older fuzzkit, of a spec whose ``NAME_controller`` is also a rule base's
name, or of a case-insensitive file system's ``Foo`` and ``foo``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from fuzzkit.errors import ConfigError

_SOURCE = re.compile(r'\b([Ff]uzzy|force-loop) controller "([A-Za-z_][A-Za-z0-9_]*)"')
_KINDS = {"fuzzy": "rule base", "force-loop": "controller spec"}
#: A first line is short; reading more of a foreign file than this is never needed.
_HEAD_BYTES = 512


def source_of(text: str) -> str | None:
    """The source a generated file names on its first line (``rule base 'in'``), or None."""
    match = _SOURCE.search(text.split("\n", 1)[0])
    if match is None:
        return None
    return f"{_KINDS[match.group(1).lower()]} {match.group(2)!r}"


def overwrite_problems(folder: Path, files: Mapping[str, str | bytes]) -> list[str]:
    """Why writing ``files`` under ``folder`` would replace another source's generated files.

    A file that does not exist, or that names the same source as its replacement, is no
    problem; nor is a file that is not fuzzkit's (no source on its first line).
    """
    problems = []
    for rel, data in files.items():
        path = folder / rel
        if not isinstance(data, str) or not path.is_file():
            continue
        with path.open("rb") as fh:
            old = source_of(fh.read(_HEAD_BYTES).decode("utf-8", errors="replace"))
        new = source_of(data)
        if old is not None and old != new:
            problems.append(
                f"{path}: generated from {old}; writing the code of {new or 'this source'} "
                "would overwrite it (give --out another folder, or delete the file)"
            )
    return problems


def refuse_overwrite(folder: Path, files: Mapping[str, str | bytes]) -> None:
    """Raise a ConfigError listing :func:`overwrite_problems`, if there are any."""
    problems = overwrite_problems(folder, files)
    if problems:
        raise ConfigError("\n".join(problems))
