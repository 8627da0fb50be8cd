"""Located YAML: the one hardened reader of every fuzzkit YAML file.

Rule bases, scenario files, gains files, robot descriptions and controller specs are all read
through this module, so they obey the same limits and report problems the same way, as
``file:line:col: message``:

- a file over :data:`MAX_FILE_BYTES` is refused before it is parsed;
- a document that expands through aliases to more than :data:`MAX_NODES` nodes (an alias
  bomb), or refers to itself, is refused without expanding it;
- a control character is refused at its line and column (YAML forbids them raw);
- explicit tags outside plain YAML (``!!python/...``) are refused;
- keys must be names: a duplicate key, a key YAML reads as a boolean (``yes``, ``on``) or a
  number is reported at the key, with the hint to quote it;
- numbers are read as YAML 1.1 does (``0x1f``, ``1_000``, ``1:30``) and also in the YAML 1.2
  exponent syntax PyYAML misses (``1e-3``); an integer too large for a float is refused at
  its line instead of overflowing later.

It knows no fuzzy logic, controller or robot, so every layer may import it (it imports only
PyYAML and :mod:`fuzzkit.errors`).

API for a new document kind
---------------------------
1. Describe it: ``KIND = DocumentKind("gains file", "gains files", "expected ...", error)``
   where ``error`` is a :class:`~fuzzkit.errors.ProblemsError` subclass
   (:class:`~fuzzkit.errors.ConfigFileError` for configuration files).
2. ``root = compose_document(read_document(path, KIND), str(path), KIND)`` (or
   :func:`load_document`, which does both) gives the located node tree.
3. Either walk it with a :class:`NodeReader` (``mapping``, ``keys``, ``number``, ``integer``,
   ``name``, ``text``, ``sequence``, ``boolean``, ``error``), which collects located problems,
   and finish with ``reader.raise_if_any(KIND)``; or convert it to plain Python data with
   :func:`to_python` and name places with :func:`locations`.

Examples
--------
>>> kind = DocumentKind("note", "notes", "expected a mapping", ConfigFileError)
>>> root = compose_document("gain: 1e-3\\n", "n.yaml", kind)
>>> reader = NodeReader("n.yaml")
>>> entries = reader.mapping(root, "a note")
>>> reader.number(entries["gain"][1], "gain")
0.001
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from fuzzkit.errors import ConfigFileError, Location, Problem, ProblemsError, did_you_mean

#: Larger files are refused before parsing: every fuzzkit YAML file is a few kilobytes.
MAX_FILE_BYTES = 1 << 20
#: Documents whose node tree, with every alias expanded, is larger are refused (alias bombs).
MAX_NODES = 100_000
#: Mappings and lists nested deeper than this are refused (PyYAML's composer recurses per level).
MAX_DEPTH = 200

STR_TAG = "tag:yaml.org,2002:str"
INT_TAG = "tag:yaml.org,2002:int"
FLOAT_TAG = "tag:yaml.org,2002:float"
BOOL_TAG = "tag:yaml.org,2002:bool"
NULL_TAG = "tag:yaml.org,2002:null"
MERGE_TAG = "tag:yaml.org,2002:merge"
_CORE_TAGS = frozenset(
    {
        STR_TAG,
        INT_TAG,
        FLOAT_TAG,
        BOOL_TAG,
        NULL_TAG,
        MERGE_TAG,
        "tag:yaml.org,2002:seq",
        "tag:yaml.org,2002:map",
    }
)
BOOL_HINT = " (YAML reads an unquoted yes/no/on/off/true/false as a boolean; quote it)"
# YAML 1.1 (PyYAML) reads ``1e-3`` as a string; accept the YAML 1.2 number syntax when unquoted.
_NUMBER_12 = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?\Z")
_CONSTRUCTOR = yaml.constructor.SafeConstructor()
_NON_PRINTABLE = yaml.reader.Reader.NON_PRINTABLE
#: Integers of more digits than a float's range holds are refused before converting.
_MAX_INT_DIGITS = 309


@dataclass(frozen=True, slots=True)
class DocumentKind:
    """What a strict YAML document holds, for the messages of :func:`compose_document`."""

    noun: str  # "rule base"
    plural: str  # "rule bases"
    empty_hint: str  # what a non-empty document has
    error: type[ProblemsError]


def describe(node: Node) -> str:
    """A node as an error message shows it: ``'abc'``, ``3``, ``true``, ``a list``."""
    if isinstance(node, ScalarNode):
        if node.tag == STR_TAG:
            shown = repr(node.value)
            return shown if len(shown) <= 60 else shown[:57] + "...'"
        if node.tag == NULL_TAG:
            return "nothing (null)" if node.value in ("", "~") else "null"
        return str(node.value) if len(node.value) <= 60 else node.value[:57] + "..."
    if isinstance(node, SequenceNode):
        return "a list"
    if isinstance(node, MappingNode):
        return "a mapping"
    return "an unknown node"  # pragma: no cover - PyYAML has no other node kinds


def location(source: str, node: Node) -> Location:
    """Where ``node`` starts in ``source`` (1-based line and column)."""
    mark = node.start_mark
    return Location(source, mark.line + 1, mark.column + 1)


def raise_problems(problems: Sequence[Problem], kind: DocumentKind) -> NoReturn:
    """Raise ``kind.error`` listing ``problems`` once each, sorted by position."""
    unique = list(dict.fromkeys(problems))
    if not unique:
        raise RuntimeError("raise_problems needs at least one problem")
    unique.sort(key=lambda p: (p.location.line, p.location.col))
    raise kind.error(unique)


class _Refused(Exception):
    """Raised to stop at once on a document that must not be processed further."""


# ---------------------------------------------------------------------------- reading


def read_text_file(
    path: str | Path, kind: DocumentKind, expected: str = "a YAML file", encoding: str = "utf-8"
) -> str:
    """The text of the file ``path`` (``expected``, e.g. ``a .fis file``), refusing with
    ``kind.error`` one over :data:`MAX_FILE_BYTES` before reading it, a folder, an unreadable
    file and one that is not text in ``encoding``."""
    p = Path(path)
    name = str(path)

    def refuse(message: str) -> NoReturn:
        raise kind.error([Problem(Location(name), message)])

    try:
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            refuse(
                f"file is {size} bytes; {kind.plural} are limited to {MAX_FILE_BYTES} bytes (1 MiB)"
            )
        data = p.read_bytes()
    except IsADirectoryError:
        refuse(f"is a directory (expected {expected})")
    except OSError as exc:
        refuse(f"cannot read: {exc.strerror or exc}")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        refuse(f"not UTF-8 text (byte {exc.start}); expected {expected}")


def read_document(path: str | Path, kind: DocumentKind) -> str:
    """The text of a strict YAML file (see :func:`read_text_file`)."""
    return read_text_file(path, kind)


def _control_characters(text: str, source: str) -> list[Problem]:
    """A problem at each control character (at most 10) that YAML does not allow raw."""
    problems: list[Problem] = []
    for m in _NON_PRINTABLE.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
        code = ord(m.group())
        problems.append(
            Problem(
                Location(source, line, col),
                f"control character U+{code:04X} is not allowed in YAML; remove it "
                f'(inside a double-quoted string write it as "\\x{code:02x}")'
                if code < 0x100
                else f"character U+{code:04X} is not allowed in YAML; remove it",
            )
        )
        if len(problems) == 10:
            break
    return problems


class _TooDeep(Exception):
    """A collection opened deeper than :data:`MAX_DEPTH`, at ``mark``."""

    def __init__(self, mark: yaml.Mark) -> None:
        super().__init__(mark)
        self.mark = mark


class _DepthLimitedLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing mappings and lists nested deeper than :data:`MAX_DEPTH`
    as it composes them (its composer recurses once per level: this stops it long before
    Python's recursion limit), in the same pass that builds the nodes."""

    depth = 0

    def compose_sequence_node(self, anchor: Any) -> SequenceNode:
        self._open()
        try:
            return super().compose_sequence_node(anchor)
        finally:
            self.depth -= 1

    def compose_mapping_node(self, anchor: Any) -> MappingNode:
        self._open()
        try:
            return super().compose_mapping_node(anchor)
        finally:
            self.depth -= 1

    def _open(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise _TooDeep(self.peek_event().start_mark)  # type: ignore[no-untyped-call]


def _compose(text: str, source: str, kind: DocumentKind) -> Node | None:
    try:
        return yaml.compose(text, Loader=_DepthLimitedLoader)
    except _TooDeep as deep:
        raise kind.error(
            [
                Problem(
                    Location(source, deep.mark.line + 1, deep.mark.column + 1),
                    f"mappings and lists nested too deeply (more than {MAX_DEPTH} levels); "
                    f"{kind.plural} are limited to {MAX_DEPTH} levels",
                )
            ]
        ) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = Location(source, mark.line + 1, mark.column + 1) if mark else Location(source)
        what = " ".join(x for x in (exc.context, exc.problem) if x) or "invalid YAML"
        if "\t" in text and "'\\t'" in what:
            what += " (YAML forbids tabs for indentation; use spaces)"
        raise kind.error([Problem(where, f"invalid YAML: {what}")]) from None
    except yaml.YAMLError as exc:
        raise kind.error([Problem(Location(source), f"invalid YAML: {exc}")]) from None
    except RecursionError:
        raise kind.error(
            [Problem(Location(source), f"invalid {kind.noun}: YAML nested too deeply")]
        ) from None


def _children(node: Node) -> list[Node]:
    if isinstance(node, SequenceNode):
        return list(node.value)
    if isinstance(node, MappingNode):
        return [x for pair in node.value for x in pair]
    return []


def _expanded_size(root: Node, limit: int) -> int:
    """Nodes in the document with every alias expanded, counting stops past ``limit``.

    Computed on the composed graph (aliases are shared nodes) without expanding anything, so
    a billion-laughs document is measured in time linear in its text.
    """
    size: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        nid = id(node)
        if done:
            on_path.discard(nid)
            total = 1 + sum(size[id(c)] for c in _children(node))
            size[nid] = min(total, limit + 1)
            if total > limit:
                return total
            continue
        if nid in size:
            continue
        on_path.add(nid)
        stack.append((node, True))
        for child in _children(node):
            if id(child) in on_path:
                raise _Refused(
                    "the document refers to itself through an alias (recursive "
                    "structure); expected a tree"
                )
            if id(child) not in size:
                stack.append((child, False))
    return size[id(root)]


def _foreign_tags(root: Node, source: str, plural: str) -> list[Problem]:
    """A problem for every node with an explicit tag outside plain YAML (``!!python/...``).

    SafeLoader would refuse to construct them; fuzzkit reads nodes itself, so it says so
    instead of silently reading the tagged value as plain data.
    """
    problems: list[Problem] = []
    seen: set[int] = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if node.tag not in _CORE_TAGS:
            problems.append(
                Problem(
                    location(source, node),
                    f"unsupported YAML tag {node.tag!r} ({plural} are plain YAML: "
                    "mappings, lists, strings and numbers)",
                )
            )
        stack.extend(_children(node))
    problems.sort(key=lambda p: (p.location.line, p.location.col))
    return problems


def compose_document(text: str, source: str, kind: DocumentKind) -> Node:
    """Compose ``text`` into a located node tree with the limits every fuzzkit YAML file obeys.

    Raises
    ------
    ProblemsError
        (``kind.error``) for a file over :data:`MAX_FILE_BYTES`, control characters, invalid
        or empty YAML, nesting deeper than :data:`MAX_DEPTH`, alias bombs and recursive
        aliases (more than :data:`MAX_NODES` nodes once expanded) and explicit tags outside
        plain YAML; every problem located in ``source``.
    """
    size = len(text.encode("utf-8", errors="replace"))
    if size > MAX_FILE_BYTES:
        raise kind.error(
            [
                Problem(
                    Location(source),
                    f"file is {size} bytes; {kind.plural} are limited to "
                    f"{MAX_FILE_BYTES} bytes (1 MiB)",
                )
            ]
        )
    controls = _control_characters(text, source)
    if controls:
        raise kind.error(controls)
    root = _compose(text, source, kind)
    if root is None:
        # nothing but comments or blank lines: point at the start, where the content belongs
        raise kind.error([Problem(Location(source, 1, 1), f"file is empty; {kind.empty_hint}")])
    try:
        nodes = _expanded_size(root, MAX_NODES)
    except _Refused as exc:
        raise kind.error([Problem(Location(source), str(exc))]) from None
    if nodes > MAX_NODES:
        raise kind.error(
            [
                Problem(
                    Location(source),
                    f"the document expands to more than {MAX_NODES} nodes through aliases "
                    f"(an alias bomb?); {kind.plural} are far smaller",
                )
            ]
        )
    foreign = _foreign_tags(root, source, kind.plural)
    if foreign:
        raise kind.error(foreign)
    return root


def load_document(path: str | Path, kind: DocumentKind) -> tuple[Node, str]:
    """The located node tree of the YAML file ``path`` and its text (see
    :func:`compose_document`)."""
    text = read_document(path, kind)
    return compose_document(text, str(path), kind), text


# ---------------------------------------------------------------------------- node reader


@dataclass
class NodeReader:
    """Converts a composed document by hand, collecting located problems instead of raising.

    Each reading method returns the value, or ``None`` after recording a problem at the node;
    a reader goes on after a problem so that one run lists them all.
    """

    file: str
    lines: list[str] = field(default_factory=list)
    problems: list[Problem] = field(default_factory=list)

    def loc(self, node: Node, column_offset: int = 0, line_offset: int = 0) -> Location:
        mark = node.start_mark
        return Location(self.file, mark.line + 1 + line_offset, mark.column + 1 + column_offset)

    def error(self, node: Node, message: str) -> None:
        """Record a problem at ``node``."""
        self.problems.append(Problem(self.loc(node), message))

    def raise_if_any(self, kind: DocumentKind) -> None:
        """Raise ``kind.error`` with every problem recorded so far (if any)."""
        if self.problems:
            raise_problems(self.problems, kind)

    def mapping(self, node: Node, what: str) -> dict[str, tuple[Node, Node]] | None:
        """The entries of a mapping node by key; reports non-mappings and duplicate keys."""
        if not isinstance(node, MappingNode):
            self.error(node, f"expected {what}, got {describe(node)}")
            return None
        entries: dict[str, tuple[Node, Node]] = {}
        for key, value in node.value:
            if key.tag == MERGE_TAG:
                self.error(key, "merge keys (<<) are not supported; write the entries out")
                continue
            if not isinstance(key, ScalarNode) or key.tag != STR_TAG:
                hint = ""
                if isinstance(key, ScalarNode):
                    hint = BOOL_HINT if key.tag == BOOL_TAG else "; quote it"
                self.error(key, f"expected a name as key, got {describe(key)}{hint}")
                continue
            if key.value in entries:
                first = entries[key.value][0].start_mark.line + 1
                self.error(key, f"duplicate key {key.value!r} (first defined on line {first})")
                continue
            entries[key.value] = (key, value)
        return entries

    def keys(
        self,
        entries: dict[str, tuple[Node, Node]],
        node: Node,
        allowed: Sequence[str],
        required: Sequence[str],
        what: str,
    ) -> None:
        """Report keys of ``entries`` not in ``allowed`` and missing ``required`` keys."""
        for key, (knode, _) in entries.items():
            if key not in allowed:
                self.error(
                    knode,
                    f"unknown key {key!r} in {what}{did_you_mean(key, allowed)}; "
                    f"expected one of {', '.join(allowed)}",
                )
        typos = {did_you_mean(k, allowed) for k in entries if k not in allowed}
        for key in required:
            # A misspelt key was reported with a did-you-mean already; one message is enough.
            if key not in entries and f" (did you mean {key!r}?)" not in typos:
                self.error(node, f"missing required key {key!r} in {what}")

    def _int_value(self, node: ScalarNode, what: str) -> int | None:
        """An integer scalar's value, refused (located) when a float cannot hold it."""
        digits = sum(c.isdigit() for c in node.value)
        too_large = f"integer of {digits} digits for {what} is too large for a float"
        if digits > _MAX_INT_DIGITS:  # checked first: int() of 4300+ digits raises
            self.error(node, f"{too_large} (at most {_MAX_INT_DIGITS - 1} digits)")
            return None
        try:
            value = int(_CONSTRUCTOR.construct_yaml_int(node))
            float(value)
        except (ValueError, OverflowError):  # a long hexadecimal or binary spelling
            self.error(node, too_large)
            return None
        return value

    def number(self, node: Node, what: str) -> float | None:
        """A float from a YAML number (1.1 or 1.2 spelling); ``inf``/``nan`` pass as such."""
        if isinstance(node, ScalarNode):
            if node.tag == FLOAT_TAG:
                return float(_CONSTRUCTOR.construct_yaml_float(node))
            if node.tag == INT_TAG:
                value = self._int_value(node, what)
                return None if value is None else float(value)
            if node.tag == STR_TAG and node.style is None and _NUMBER_12.match(node.value):
                return float(node.value)
        self.error(node, f"expected a number for {what}, got {describe(node)}")
        return None

    def finite(
        self, node: Node, what: str, low: float = -math.inf, high: float = math.inf
    ) -> float | None:
        """A finite number in ``[low, high]``; the message names the bounds."""
        value = self.number(node, what)
        if value is None:
            return None
        if not (math.isfinite(value) and low <= value <= high):
            bounds = (
                f" in [{low:g}, {high:g}]"
                if math.isfinite(low) and math.isfinite(high)
                else f" >= {low:g}"
                if math.isfinite(low)
                else f" <= {high:g}"
                if math.isfinite(high)
                else ""
            )
            self.error(node, f"{what} must be a finite number{bounds} (got {value:g})")
            return None
        return value

    def integer(
        self, node: Node, what: str, minimum: int = 0, maximum: int | None = None
    ) -> int | None:
        """An integer in ``[minimum, maximum]`` in any YAML 1.1 spelling (``0x1``, ``1_0``)."""
        if isinstance(node, ScalarNode) and node.tag == INT_TAG:
            value = self._int_value(node, what)
            if value is None:
                return None
            if value >= minimum and (maximum is None or value <= maximum):
                return value
        upper = f" (at most {maximum})" if maximum is not None else ""
        self.error(
            node, f"expected an integer >= {minimum} for {what}{upper}, got {describe(node)}"
        )
        return None

    def boolean(self, node: Node, what: str) -> bool | None:
        if isinstance(node, ScalarNode) and node.tag == BOOL_TAG:
            return bool(_CONSTRUCTOR.construct_yaml_bool(node))
        self.error(node, f"expected true or false for {what}, got {describe(node)}")
        return None

    def name(self, node: Node, what: str) -> str | None:
        """A string scalar; a boolean gets the hint to quote it."""
        if isinstance(node, ScalarNode) and node.tag == STR_TAG:
            return str(node.value)
        hint = BOOL_HINT if isinstance(node, ScalarNode) and node.tag == BOOL_TAG else ""
        self.error(node, f"expected {what}, got {describe(node)}{hint}")
        return None

    def text(self, node: Node, what: str) -> str | None:
        if isinstance(node, ScalarNode) and node.tag == STR_TAG:
            return str(node.value)
        self.error(node, f"expected {what} (a string), got {describe(node)}")
        return None

    def sequence(self, node: Node, what: str) -> list[Node] | None:
        if isinstance(node, SequenceNode):
            return list(node.value)
        self.error(node, f"expected {what} (a list), got {describe(node)}")
        return None


# ---------------------------------------------------------------------------- plain data


def to_python(root: Node, source: str, kind: DocumentKind) -> Any:
    """Plain Python data (dict, list, str, int, float, bool, None) from a composed tree.

    Keys are checked as :meth:`NodeReader.mapping` does (names only, no duplicates); numbers
    as :meth:`NodeReader.number` (``1e-3`` is a float, huge integers are refused).

    Raises
    ------
    ProblemsError
        (``kind.error``) listing every problem, located.
    """
    reader = NodeReader(source)

    def convert(node: Node) -> Any:
        if isinstance(node, MappingNode):
            entries = reader.mapping(node, "a mapping") or {}
            return {k: convert(v) for k, (_, v) in entries.items()}
        if isinstance(node, SequenceNode):
            return [convert(item) for item in node.value]
        if not isinstance(node, ScalarNode):  # pragma: no cover - no other node kinds
            raise RuntimeError(f"unexpected YAML node {node!r}")
        if node.tag == INT_TAG:
            return reader._int_value(node, "a number")
        if node.tag in (FLOAT_TAG, STR_TAG):
            if node.tag == FLOAT_TAG or (node.style is None and _NUMBER_12.match(node.value)):
                return reader.number(node, "a number")
            return str(node.value)
        if node.tag == BOOL_TAG:
            return bool(_CONSTRUCTOR.construct_yaml_bool(node))
        return None  # null

    data = convert(root)
    reader.raise_if_any(kind)
    return data


def locations(root: Node, source: str) -> dict[tuple[str | int, ...], Location]:
    """Where each key path of a composed tree is written: mapping keys by name, list items
    by index (``("joints", 2, "limits")``); ``()`` is the document."""
    out: dict[tuple[str | int, ...], Location] = {(): location(source, root)}
    stack: list[tuple[Node, tuple[str | int, ...]]] = [(root, ())]
    while stack:
        node, path = stack.pop()
        if isinstance(node, MappingNode):
            for key, value in node.value:
                sub = (*path, str(key.value))
                out.setdefault(sub, location(source, key))
                stack.append((value, sub))
        elif isinstance(node, SequenceNode):
            for i, item in enumerate(node.value):
                out[(*path, i)] = location(source, item)
                stack.append((item, (*path, i)))
    return out


__all__ = [
    "BOOL_TAG",
    "FLOAT_TAG",
    "INT_TAG",
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_NODES",
    "NULL_TAG",
    "STR_TAG",
    "ConfigFileError",
    "DocumentKind",
    "NodeReader",
    "compose_document",
    "describe",
    "load_document",
    "location",
    "locations",
    "raise_problems",
    "read_document",
    "read_text_file",
    "to_python",
]
