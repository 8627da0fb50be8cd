"""Which doc commands depend on which, and the test items that run each distinct one once.

A command *writes* the paths named by its output options (:data:`OUTPUT_OPTIONS`) or a shell
``>``, and *reads* every other word it names. It depends on the latest earlier command of its
page that writes a path it reads, or one it writes again (a command may merge into an existing
output: ``tune --out`` does). A page's commands joined by dependencies form a *group*: run in
order in one scratch folder, a group needs nothing from any other, so groups run in parallel.

A command's *key* is its text as run (after ``LIMITS``) with the keys of the commands it
depends on: two places with one key run the same command in the same working-folder state. The
plan runs every key once, in the first group that holds it, and names all its places.
"""

from __future__ import annotations

import fnmatch
import shlex
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from tests._doc_commands import PAGES, Command, commands, limited, not_run_reason

#: The options whose value is a path the command writes (every other word it names is read).
#: Checked as the commands run: a command that writes a path none of these names fails there.
OUTPUT_OPTIONS = frozenset(
    {"--out", "--png", "--rrd", "--csv", "--spec-out", "--rrd-dir", "--png-dir", "--csv-dir"}
)
#: Words that start a new shell command or redirect one: what follows ``>`` is written.
_REDIRECTS = frozenset({">", ">>"})
#: Outputs a subcommand writes without an option naming them: ``(subcommand, option left
#: out)`` -> the path it writes, from the argv (``sweep --out runs.csv`` draws ``runs.png``).
IMPLIED_OUTPUTS = {
    ("sweep", "--png"): lambda ws: _path(ws[ws.index("--out") + 1]).with_suffix(".png"),
}


def words(text: str) -> list[str]:
    """The command's words as a shell splits them (an operator such as ``>`` is a word)."""
    lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    return list(lexer)


def _path(word: str) -> PurePosixPath:
    return PurePosixPath(word.rstrip("/") or "/")


def writes(text: str) -> set[PurePosixPath]:
    """The paths ``text`` writes: its output options' values, its ``>`` target and what its
    subcommand writes unasked (:data:`IMPLIED_OUTPUTS`)."""
    ws = words(text)
    named = {_path(ws[i + 1]) for i, w in enumerate(ws[:-1]) if w in OUTPUT_OPTIONS | _REDIRECTS}
    implied = {
        implied(ws)
        for (subcommand, option), implied in IMPLIED_OUTPUTS.items()
        if ws[1:2] == [subcommand] and option not in ws and "--out" in ws
    }
    return named | implied


def reads(text: str) -> set[str]:
    """Every other word ``text`` names, comma-separated lists split (``--spec a.yaml,b.yaml``):
    the paths it may read (most are not paths at all, and match nothing a command writes)."""
    ws = words(text)
    out: set[str] = set()
    for i, w in enumerate(ws[2:], start=2):
        if w.startswith("-") or w in _REDIRECTS or ws[i - 1] in OUTPUT_OPTIONS | _REDIRECTS:
            continue
        out.update(part for part in w.split(",") if part)
    return out


def _touches(word: str, written: PurePosixPath) -> bool:
    """Whether the word (a path or a glob) names ``written`` or a path inside it."""
    path = _path(word)
    if any(ch in word for ch in "*?["):
        return fnmatch.fnmatch(str(written), word) or any(
            fnmatch.fnmatch(str(p), word) for p in written.parents
        )
    return path == written or written in path.parents


@dataclass(frozen=True)
class Step:
    """One command of a group: its text as run, its key, the place of the page the group
    comes from, every place of the docs that runs it (that one included), and the paths
    that earlier commands of those pages write and it does not name (were it to read one,
    it would depend on a command the plan does not run before it)."""

    text: str
    key: tuple[object, ...]
    home: Command
    places: tuple[Command, ...]
    unnamed: frozenset[PurePosixPath] = frozenset()

    @property
    def subcommand(self) -> str:
        ws = words(self.text)
        return ws[1] if len(ws) > 1 else ws[0]

    @property
    def where(self) -> str:
        """Every place of the command, ``page:line`` joined by commas."""
        return ", ".join(p.where for p in self.places)

    @property
    def outputs(self) -> set[PurePosixPath]:
        return writes(self.text)


@dataclass(frozen=True)
class Group:
    """Commands that run in order in one scratch folder: a command with the earlier ones of
    its page that produce the files it names."""

    steps: tuple[Step, ...]

    @property
    def id(self) -> str:
        """``page:line-subcommand`` of the first step, ``+N`` for N more (a test id)."""
        first = self.steps[0]
        more = f"+{len(self.steps) - 1}" if len(self.steps) > 1 else ""
        return f"{first.home.page.name}:{first.home.line}-{first.subcommand}{more}"


def dependencies(texts: list[str]) -> list[list[int]]:
    """For each command, the earlier ones (indices) it depends on (module docstring)."""
    out: list[list[int]] = []
    written = [writes(text) for text in texts]
    for i, text in enumerate(texts):
        named = reads(text) | {str(p) for p in written[i]}
        deps = set()
        for word in named:
            writers = [j for j in range(i) if any(_touches(word, w) for w in written[j])]
            if writers:
                deps.add(writers[-1])
        out.append(sorted(deps))
    return out


def _components(deps: list[list[int]]) -> list[list[int]]:
    """The commands joined by dependencies, each group in page order."""
    root = list(range(len(deps)))

    def find(i: int) -> int:
        while root[i] != i:
            i = root[i]
        return i

    for i, ds in enumerate(deps):
        for j in ds:
            root[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(len(deps)):
        groups.setdefault(find(i), []).append(i)
    return sorted(groups.values())


def keys(texts: list[str]) -> list[tuple[object, ...]]:
    """Each command's key, when ``texts`` run in order in one folder (module docstring)."""
    out: list[tuple[object, ...]] = []
    for text, deps in zip(texts, dependencies(texts), strict=True):
        out.append((text, *(out[j] for j in deps)))
    return out


@dataclass(frozen=True)
class _Found:
    """A command where a page shows it: its key, the command, its text as run, and the
    paths earlier commands of the page write that it does not name."""

    key: tuple[object, ...]
    command: Command
    text: str
    unnamed: frozenset[PurePosixPath]


def _page_groups(page: Path) -> list[list[_Found]]:
    """The page's commands, in groups."""
    cmds = [c for c in commands(page) if not_run_reason(c.text) is None]
    texts = [limited(c.text) for c in cmds]
    ks = keys(texts)
    found = []
    for i, text in enumerate(texts):
        named = reads(text) | {str(p) for p in writes(text)}
        earlier = {w for t in texts[:i] for w in writes(t)}
        unnamed = {w for w in earlier if not any(_touches(word, w) for word in named)}
        found.append(_Found(ks[i], cmds[i], text, frozenset(unnamed)))
    return [[found[i] for i in comp] for comp in _components(dependencies(texts))]


def plan(pages: Iterable[Path] = PAGES) -> list[Group]:
    """The groups that run every distinct command of ``pages`` once, in the docs' order.

    A page's group whose every key an earlier group runs is dropped (a page repeating
    another's commands). One that shares a key with an earlier group is appended to it when
    its own commands, run after that group's, keep their keys (they name nothing the earlier
    group alone writes); else it is kept whole, running the shared commands again, since
    its commands need their files."""
    page_groups = [g for page in pages for g in _page_groups(page)]
    places: dict[tuple[object, ...], list[Command]] = {}
    unnamed: dict[tuple[object, ...], frozenset[PurePosixPath]] = {}
    for f in (f for group in page_groups for f in group):
        places.setdefault(f.key, []).append(f.command)
        unnamed[f.key] = unnamed.get(f.key, frozenset()) | f.unnamed
    kept: list[list[Step]] = []
    for group in page_groups:
        steps = [
            Step(f.text, f.key, f.command, tuple(places[f.key]), unnamed[f.key]) for f in group
        ]
        runs = {s.key for g in kept for s in g}
        new = [s for s in steps if s.key not in runs]
        if not new:
            continue
        shared = {s.key for s in steps} - {s.key for s in new}
        for earlier in (g for g in kept if shared and shared <= {s.key for s in g}):
            merged = [*earlier, *new]
            if keys([s.text for s in merged]) == [s.key for s in merged]:
                earlier.extend(new)
                break
        else:
            kept.append(steps)
    return [Group(tuple(g)) for g in kept]
