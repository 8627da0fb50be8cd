"""What a code-generation target is: every choice its folder ``backends/<target>/`` makes.

Shared code (the spec builders of :mod:`~fuzzkit.codegen.emit`, :mod:`~fuzzkit.codegen.exact`
and :mod:`~fuzzkit.codegen.controller`, the CLI) never asks which target it serves; it asks
the :class:`Target` that ``backends/<target>/config.py`` defines as ``TARGET``: how a number is
written, how ``min``/``max`` are spelt, which words are reserved, which number types the
target computes in, which templates make which files, and how the output is proven (compiled
or imported). A target is a folder: :data:`TARGETS` lists the folders found.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from fuzzkit.errors import CodegenError

if TYPE_CHECKING:
    from fuzzkit.codegen.lookup_table import LookupTable
    from fuzzkit.codegen.progress import ProgressFn
    from fuzzkit.fuzzy.model import RuleBase

BACKENDS = Path(__file__).parent / "backends"

#: Every target: one folder with a ``config.py`` under ``backends/``, in name order.
TARGETS: tuple[str, ...] = tuple(
    sorted(p.parent.name for p in BACKENDS.glob("*/config.py") if p.parent.name.isidentifier())
)

#: The artefacts a target can make, each from its own spec object: a rule base as a lookup
#: table (``emit.TableSpec``) or as the exact inference (``exact.ExactSpec``), and the whole
#: outer-loop controller (``controller.ControllerCodeSpec``).
ARTEFACTS = ("table", "exact", "controller")


class Proof(Protocol):
    """The outcome of verifying generated code (``verify.Verification``)."""

    @property
    def ok(self) -> bool:
        """True when the generated code matched its reference."""

    def describe(self) -> str:
        """One line for humans."""


class VerifyTable(Protocol):
    """Compile or import a generated table and compare it with the exact engine, reporting
    the points evaluated to ``progress`` (``verify.verify_c``)."""

    def __call__(
        self,
        rb: RuleBase,
        table: LookupTable,
        files: Mapping[str, str],
        *,
        progress: ProgressFn | None = None,
    ) -> Proof:
        """The outcome."""


class VerifyExact(Protocol):
    """The same for exact-method code in ``number_type`` (``verify.verify_exact_c``)."""

    def __call__(
        self,
        rb: RuleBase,
        number_type: str,
        files: Mapping[str, str],
        *,
        progress: ProgressFn | None = None,
    ) -> Proof:
        """The outcome."""


@dataclass(frozen=True)
class Target:
    """The choices of one target language; built once in ``backends/<name>/config.py``."""

    #: The folder name, as ``--target`` takes it.
    name: str
    #: How people write the language's name ("C", "Python") in messages.
    label: str
    #: The folder holding the templates (``backends/<name>/``).
    folder: Path
    #: Number types it computes in, and the one ``fuzzkit compile`` takes without ``--type``.
    number_types: tuple[str, ...]
    default_number_type: str
    #: Each number type's spelling in the language (``"int16_t"`` for q15 in C).
    type_names: Mapping[str, str]
    #: Suffix of the math library's functions per number type (C: ``expf`` for float).
    math_suffix: Mapping[str, str]
    #: How generated notes name each number type's arithmetic ("double arithmetic").
    runtime: Mapping[str, str]
    #: ``literal(value, number_type)``: a finite constant as source text.
    literal: Callable[[float, str], str]
    #: A NaN constant as source text.
    nan: str
    #: Callee spelling of the helpers the generated code calls: ``min``, ``max``, ``psum``
    #: (``{name}`` is the rule base's name: C prefixes every symbol with it).
    functions: Mapping[str, str]
    #: Words a generated name must not be (keywords, reserved identifiers).
    reserved_words: frozenset[str]
    #: ``module_clash(name)``: why a file named after ``name`` would shadow a standard module
    #: or header of the language, or None.
    module_clash: Callable[[str], str | None]
    #: Literals per line of a data array, per artefact (the lines stay under 100 columns).
    values_per_line: Mapping[str, int]
    #: Per artefact: output path pattern (``{name}``) -> template in the target's folder.
    files: Mapping[str, Mapping[str, str]]
    #: Exact method: the templates visit only the rule cells that can fire (2-input tables).
    visits_firing_cells: bool
    #: Exact method: the templates take the engine's polynomial centroid where it applies.
    fast_centroid: bool
    #: Proof of a table / an exact-method output: compile or import it and compare it with
    #: the exact engine (``fuzzkit compile --verify``).
    verify_table: VerifyTable
    verify_exact: VerifyExact
    #: Build and load a generated controller: ``open_controller(files, name, number_type)``
    #: returns an object with ``step(force_n, tool_rotation) -> (correction, status)``.
    open_controller: Callable[[Mapping[str, str], str, str], Any] | None = None
    #: Per number type, the math functions its exact code computes itself rather than call
    #: (C float: exp, log, erfc, pow, whose libm versions differ by an ulp between C libraries).
    portable_math: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    #: A target whose templates this one reuses: a template missing from ``folder`` is taken
    #: from that target's folder (the FMU target lays the C target's controller out as is).
    extends: str | None = None
    #: A target whose output is one file rather than a folder: ``bundle(files, name)`` turns
    #: the rendered files into its bytes (the FMU: compile the binary, zip everything).
    bundle: Callable[[Mapping[str, str], str], bytes] | None = None
    #: The controller keeps its gains, set points and safety limit in the caller's state, set
    #: from the spec by init and changeable between steps (the FMU's tunable parameters),
    #: rather than as ``static const`` data.
    tunable_parameters: bool = False

    def template_folders(self) -> list[Path]:
        """Where this target's templates are looked up: its folder, then the extended one's."""
        folders = [self.folder]
        if self.extends is not None:
            folders.extend(load_target(self.extends).template_folders())
        return folders

    def check_number_type(self, number_type: str, what: str) -> None:
        """Raise CodegenError unless the target computes in ``number_type``."""
        if number_type not in self.number_types:
            raise CodegenError(
                f"the {self.name} target computes in {' or '.join(self.number_types)}; got {what}"
            )


@cache
def load_target(name: str) -> Target:
    """The :class:`Target` of ``backends/<name>/``.

    Raises
    ------
    CodegenError
        No such folder.
    """
    if name not in TARGETS:
        raise CodegenError(f"unknown target {name!r} (expected one of {', '.join(TARGETS)})")
    config = importlib.import_module(f"fuzzkit.codegen.backends.{name}.config")
    target: Target = config.TARGET
    return target


def all_targets() -> tuple[Target, ...]:
    """Every target, in :data:`TARGETS` order."""
    return tuple(load_target(name) for name in TARGETS)


__all__ = ["ARTEFACTS", "TARGETS", "Target", "all_targets", "load_target"]
