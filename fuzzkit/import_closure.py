"""The package modules a module can reach through its imports, and one digest of their sources.

This is the cache key of a compiled kernel (:mod:`fuzzkit.jit`): numba freezes a kernel's
callees and the module globals it reads (constants) into the machine code it caches, so the
cached code is stale as soon as any module whose functions or globals the kernel can reach
changes, and only then.

What counts as reachable (a sound superset, from the source alone, with :mod:`ast`):

- the modules a module *binds names from* at module scope: ``import a.b.c`` binds ``a`` (so
  ``a``, ``a.b`` and ``a.b.c`` are all reachable through attributes), ``import a.b.c as m``
  binds ``a.b.c``, ``from a.b import y`` binds the submodule ``a.b.y`` when there is one, else
  a name defined in ``a.b``; relative imports resolve against the module's package; an import
  inside an ``if``, ``try`` or class body counts, since it runs at import;
- then, transitively, the same for each of those modules: a name imported from ``a.b`` may be
  a constant computed from what ``a.b`` imports, or a kernel calling further kernels.

Two things are deliberately *not* followed, because neither can change what a kernel reaches:

- imports inside a function body: they bind a local of a Python function, and a kernel can
  neither call a Python function nor see its locals (``generated_controller.py`` imports the
  code generator that way; following it would put most of the package back in the key);
- the packages above what is imported: ``from fuzzkit.plants.arm6 import X`` (or ``from
  fuzzkit.plants import arm6``) runs ``fuzzkit/plants/__init__.py`` too, but binds only what
  ``arm6`` defines (or ``arm6`` itself). A package a name is imported from, ``from
  fuzzkit.planar_sim import PlanarArmPlant``, is followed. (A package ``__init__`` that
  imported everything would otherwise put the whole package back in every key.)

Parsing is the one cost (a few hundred milliseconds for the run loops' closures); what a file's
parse found is kept beside its bytecode, ``__pycache__/NAME.imports.json``, keyed by the
sha256 of its source as a ``.pyc`` is by its stamp, so a process parses only what was edited
since (:class:`ImportGraph` with ``keep=True``; a folder that cannot be written just parses).

Only modules inside the given roots are followed (the package and the folders mapped into it);
numpy, numba and the standard library are numba's own business (its cache is per version).
Names reached by other means (``importlib.import_module``, monkeypatching) are not seen: no
module of the package does that to a kernel's globals.
"""

from __future__ import annotations

import ast
import hashlib
import json
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import write_atomic


@dataclass(frozen=True, slots=True)
class ImportStatement:
    """What decides which modules one import statement binds names from: ``import names``
    (``aliased``: which of them have an ``as``), or ``from module import names`` at ``level``
    (the leading dots of a relative import)."""

    is_from: bool
    level: int
    module: str
    names: tuple[str, ...]
    aliased: tuple[bool, ...]

    @classmethod
    def of(cls, node: ast.Import | ast.ImportFrom) -> ImportStatement:
        """The statement of an ``import`` or ``from ... import`` node."""
        names = tuple(alias.name for alias in node.names)
        aliased = tuple(alias.asname is not None for alias in node.names)
        if isinstance(node, ast.Import):
            return cls(False, 0, "", names, aliased)
        return cls(True, node.level, node.module or "", names, aliased)


class ImportGraph:
    """The module-scope imports between the modules under ``roots``, each file parsed once.

    ``roots`` maps a package name to the folder holding its source: ``{"fuzzkit":
    Path("fuzzkit"), "fuzzkit.codegen": Path("codegen")}`` (the longest name that prefixes a
    module wins). The graph reads files when first asked about them and remembers the answer:
    make a new graph to see an edited tree. ``keep``: keep each parse on disk (see the module
    docstring) and reuse the kept parses whose source is unchanged.
    """

    def __init__(self, roots: Mapping[str, Path], *, keep: bool = False) -> None:
        self._keep = keep
        # longest package name first, so that a mapped subpackage wins over its parent
        self._roots = sorted(
            ((name, Path(folder).resolve()) for name, folder in roots.items()),
            key=lambda item: -len(item[0]),
        )
        self._paths: dict[str, Path | None] = {}
        self._sources: dict[Path, bytes] = {}
        self._imports: dict[str, frozenset[str]] = {}
        self._closures: dict[str, dict[str, Path]] = {}
        self._digests: dict[str, str] = {}

    def path_of(self, module: str) -> Path | None:
        """The source file of ``module`` (a package's ``__init__.py``), or None when it is not
        under the roots or has no source file."""
        if module not in self._paths:
            self._paths[module] = self._find(module)
        return self._paths[module]

    def _find(self, module: str) -> Path | None:
        for name, folder in self._roots:
            if module == name or module.startswith(name + "."):
                base = folder.joinpath(*module[len(name) :].split(".")[1:])
                for path in (base / "__init__.py", base.with_suffix(".py")):
                    if path.is_file():
                        return path
                return None
        return None

    def module_of(self, path: Path) -> str | None:
        """The module whose source file is ``path``, or None when it is not under the roots."""
        resolved = Path(path).resolve()
        for name, folder in self._roots:
            if resolved.suffix == ".py" and resolved.is_relative_to(folder):
                parts = resolved.relative_to(folder).with_suffix("").parts
                if parts[-1:] == ("__init__",):
                    parts = parts[:-1]
                module = ".".join((name, *parts))
                if self.path_of(module) == resolved:
                    return module
        return None

    def imports(self, module: str) -> frozenset[str]:
        """The modules under the roots that ``module`` binds names from at module scope."""
        if module not in self._imports:
            path = self.path_of(module)
            found: set[str] = set()
            if path is not None:
                package = module if path.name == "__init__.py" else module.rpartition(".")[0]
                for statement in self._statements(path):
                    found.update(self._bound_from(statement, package))
            self._imports[module] = frozenset(found)
        return self._imports[module]

    def closure(self, module: str) -> tuple[str, ...]:
        """``module`` and every module it reaches through :meth:`imports`, sorted."""
        return tuple(sorted(self._closure_files(module)))

    def digest(self, module: str) -> str:
        """sha256 over the name and source of every module of :meth:`closure`: a rename or a
        move changes it as an edit does."""
        if module not in self._digests:
            sha = hashlib.sha256()
            for name, path in sorted(self._closure_files(module).items()):
                sha.update(name.encode("utf-8") + b"\0" + self._source(path) + b"\0")
            self._digests[module] = sha.hexdigest()
        return self._digests[module]

    def _closure_files(self, module: str) -> dict[str, Path]:
        """:meth:`closure` with each module's source file."""
        if module not in self._closures:
            found: dict[str, Path] = {}
            todo = [module]
            while todo:
                current = todo.pop()
                path = self.path_of(current)
                if current not in found and path is not None:
                    found[current] = path
                    todo.extend(self.imports(current))
            self._closures[module] = found
        return self._closures[module]

    def _bound_from(self, statement: ImportStatement, package: str) -> Iterator[str]:
        """The modules under the roots that one import statement binds names from."""
        if not statement.is_from:
            for name, aliased in zip(statement.names, statement.aliased, strict=True):
                parts = name.split(".")
                # `import a.b.c` binds `a`: every prefix is reachable; `as m` binds the last only
                first = len(parts) if aliased else 1
                for end in range(first, len(parts) + 1):
                    yield from self._known(".".join(parts[:end]))
            return
        base = statement.module
        if statement.level:
            up = package.split(".")[: len(package.split(".")) - (statement.level - 1)]
            base = ".".join([*up, base] if base else up)
        for name in statement.names:
            # `from a.b import y` binds the submodule a.b.y if there is one, else a name of a.b
            submodule = f"{base}.{name}"
            if name != "*" and self.path_of(submodule) is not None:
                yield submodule
            else:
                yield from self._known(base)

    def _source(self, path: Path) -> bytes:
        """The bytes of ``path``, read once: the parse and the digest see the same text."""
        if path not in self._sources:
            self._sources[path] = path.read_bytes()
        return self._sources[path]

    def _statements(self, path: Path) -> tuple[ImportStatement, ...]:
        """The module-scope import statements of the source file ``path``, parsed or kept."""
        source = self._source(path)
        if not self._keep:
            return _parse(source, path)
        sha = hashlib.sha256(source).hexdigest()
        kept = path.parent / "__pycache__" / f"{path.stem}.imports.json"
        try:
            data = json.loads(kept.read_bytes())
            if data["sha256"] == sha:
                return tuple(
                    ImportStatement(f, lv, m, tuple(n), tuple(a))
                    for f, lv, m, n, a in data["statements"]
                )
        except (OSError, ValueError, KeyError, TypeError):
            pass  # none kept yet, or unreadable: parse
        statements = _parse(source, path)
        rows = [[s.is_from, s.level, s.module, s.names, s.aliased] for s in statements]
        try:
            kept.parent.mkdir(exist_ok=True)
            write_atomic(kept, json.dumps({"sha256": sha, "statements": rows}))
        except (OSError, ConfigError):
            pass  # a read-only install parses in every process: slower, never wrong
        return statements

    def _known(self, module: str) -> Iterator[str]:
        if self.path_of(module) is not None:
            yield module


def _parse(source: bytes, path: Path) -> tuple[ImportStatement, ...]:
    """The module-scope import statements of a module's source."""
    tree = ast.parse(source, filename=str(path))
    return tuple(ImportStatement.of(node) for node in _module_scope(tree))


def _module_scope(tree: ast.Module) -> Iterator[ast.Import | ast.ImportFrom]:
    """The import statements that run when the module is imported: every one outside a
    function body. Only statements are visited (an expression holds no import statement)."""
    todo: list[ast.stmt] = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            # the statement lists of if/else, try/except/finally, with, for, while, match, class
            for field in ("body", "orelse", "finalbody"):
                todo.extend(getattr(node, field, ()))
            for part in (*getattr(node, "handlers", ()), *getattr(node, "cases", ())):
                todo.extend(part.body)
