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

Only modules inside the given roots are followed (the package and the folders mapped into it);
numpy, numba and the standard library are numba's own business (its cache is per version).
Names reached by other means (``importlib.import_module``, monkeypatching) are not seen: no
module of the package does that to a kernel's globals.
"""

from __future__ import annotations

import ast
import hashlib
from collections.abc import Iterator, Mapping
from pathlib import Path


class ImportGraph:
    """The module-scope imports between the modules under ``roots``, each file parsed once.

    ``roots`` maps a package name to the folder holding its source: ``{"fuzzkit":
    Path("fuzzkit"), "fuzzkit.codegen": Path("codegen")}`` (the longest name that prefixes a
    module wins). The graph reads files when first asked about them and remembers the answer:
    make a new graph to see an edited tree.
    """

    def __init__(self, roots: Mapping[str, Path]) -> None:
        # longest package name first, so that a mapped subpackage wins over its parent
        self._roots = sorted(
            ((name, Path(folder).resolve()) for name, folder in roots.items()),
            key=lambda item: -len(item[0]),
        )
        self._imports: dict[str, frozenset[str]] = {}
        self._closures: dict[str, dict[str, Path]] = {}
        self._digests: dict[str, str] = {}

    def path_of(self, module: str) -> Path | None:
        """The source file of ``module`` (a package's ``__init__.py``), or None when it is not
        under the roots or has no source file."""
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
                tree = ast.parse(path.read_bytes(), filename=str(path))
                package = module if path.name == "__init__.py" else module.rpartition(".")[0]
                for node in _module_scope(tree):
                    found.update(self._bound_from(node, package))
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
                sha.update(name.encode("utf-8") + b"\0" + path.read_bytes() + b"\0")
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

    def _bound_from(self, node: ast.Import | ast.ImportFrom, package: str) -> Iterator[str]:
        """The modules under the roots that one import statement binds names from."""
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                # `import a.b.c` binds `a`: every prefix is reachable; `as m` binds the last only
                first = len(parts) if alias.asname else 1
                for end in range(first, len(parts) + 1):
                    yield from self._known(".".join(parts[:end]))
            return
        base = node.module or ""
        if node.level:
            up = package.split(".")[: len(package.split(".")) - (node.level - 1)]
            base = ".".join([*up, base] if base else up)
        for alias in node.names:
            # `from a.b import y` binds the submodule a.b.y if there is one, else a name of a.b
            submodule = f"{base}.{alias.name}"
            if alias.name != "*" and self.path_of(submodule) is not None:
                yield submodule
            else:
                yield from self._known(base)

    def _known(self, module: str) -> Iterator[str]:
        if self.path_of(module) is not None:
            yield module


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
