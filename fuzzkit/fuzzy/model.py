"""The frozen rule-base model: the one structure every engine and emitter reads.

The model knows no file format (``fuzzkit.formats`` reads and writes files) and prints no code
(``fuzzkit.codegen`` does). Every object is a frozen, slotted dataclass holding tuples, so a model
is hashable, comparable and safe to share between threads and processes.

Semantic consistency (ordered term parameters, known labels, covered input ranges, identifier
names) is checked by :func:`fuzzkit.fuzzy.validation.check`, which the YAML loader and every engine
call; constructing these classes by hand does not check anything by itself.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, TypeAlias

from fuzzkit.fuzzy.display import NotebookDisplay

# The shape vocabulary is the registry's (fuzzkit.fuzzy.shapes), re-exported here.
from fuzzkit.fuzzy.shapes import PIECEWISE_LINEAR_SHAPES as PIECEWISE_LINEAR_SHAPES
from fuzzkit.fuzzy.shapes import SHAPE_PARAMS as SHAPE_PARAMS
from fuzzkit.fuzzy.shapes import SUGENO_SHAPES as SUGENO_SHAPES

AND_OPERATORS = ("min", "product")
OR_OPERATORS = ("max", "probabilistic_sum")
IMPLICATIONS = ("min", "product")
AGGREGATIONS = ("max", "bounded_sum", "probabilistic_sum")
DEFUZZIFIERS = (
    "centroid",
    "bisector",
    "mean_of_maximum",
    "smallest_of_maximum",
    "largest_of_maximum",
    "weighted_average",
    "weighted_sum",
)
#: Defuzzifiers of Sugeno outputs (``sum(w z) / sum(w)`` and ``sum(w z)`` over the rules).
SUGENO_DEFUZZIFIERS = ("weighted_average", "weighted_sum")
#: What happens to an input outside its declared range: ``clamp`` (default) evaluates the
#: membership functions at the nearest range end; ``extend`` evaluates them where the input is.
OUT_OF_RANGE_POLICIES = ("clamp", "extend")
#: What an input range with no term above zero is: ``strict`` (default) makes it an error,
#: ``allow_gaps`` a warning (rules cannot fire there; outputs take their default or NaN).
COVERAGE_POLICIES = ("strict", "allow_gaps")

AndOperator: TypeAlias = Literal["min", "product"]
OrOperator: TypeAlias = Literal["max", "probabilistic_sum"]
Implication: TypeAlias = Literal["min", "product"]
Aggregation: TypeAlias = Literal["max", "bounded_sum", "probabilistic_sum"]
Defuzzifier: TypeAlias = Literal[
    "centroid",
    "bisector",
    "mean_of_maximum",
    "smallest_of_maximum",
    "largest_of_maximum",
    "weighted_average",
    "weighted_sum",
]
OutOfRange: TypeAlias = Literal["clamp", "extend"]


@dataclass(frozen=True, slots=True)
class Term:
    """A linguistic label of a variable: a name, a shape and its parameters (fuzzy.shapes)."""

    name: str
    shape: str
    params: tuple[float, ...]

    @property
    def is_piecewise_linear(self) -> bool:
        return self.shape in PIECEWISE_LINEAR_SHAPES

    @property
    def is_sugeno(self) -> bool:
        """A Sugeno output term (``constant`` or ``linear``) rather than a membership function."""
        return self.shape in SUGENO_SHAPES


@dataclass(frozen=True, slots=True)
class Variable:
    """An input or output variable: its universe ``[low, high]`` and its terms.

    ``default`` is used for an output when no rule fires (``None`` means NaN); it is ignored
    for inputs. ``units`` is the physical unit of the variable's values (``"N"``, ``"mm"``,
    ``"%"``), for display only: labels, headers and recordings; ``None`` when unitless or unknown.
    """

    name: str
    low: float
    high: float
    terms: tuple[Term, ...]
    default: float | None = None
    units: str | None = None

    @property
    def term_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.terms)

    @property
    def is_sugeno(self) -> bool:
        """An output whose terms are Sugeno terms (validation makes them all one family)."""
        return bool(self.terms) and all(t.is_sugeno for t in self.terms)

    def term_index(self, name: str) -> int:
        """Index of the term called ``name``; ``KeyError`` if there is none."""
        for i, t in enumerate(self.terms):
            if t.name == name:
                return i
        raise KeyError(name)

    def term(self, name: str) -> Term:
        return self.terms[self.term_index(name)]


@dataclass(frozen=True, slots=True)
class Proposition:
    """``variable is term`` (or ``is not`` when ``negated``); NOT is ``1 - mu``."""

    variable: str
    term: str
    negated: bool = False


@dataclass(frozen=True, slots=True)
class Compound:
    """AND or OR of two or more sub-expressions, using the rule base's operators."""

    op: Literal["and", "or"]
    operands: tuple[Expression, ...]


Expression: TypeAlias = Proposition | Compound


@dataclass(frozen=True, slots=True)
class Consequent:
    """``then variable is term``."""

    variable: str
    term: str


@dataclass(frozen=True, slots=True)
class Rule:
    """IF antecedent THEN consequents, with a weight in [0, 1] multiplying the firing strength."""

    antecedent: Expression
    consequents: tuple[Consequent, ...]
    weight: float = 1.0


@dataclass(frozen=True, slots=True)
class Operators:
    """The fuzzy operators of a rule base."""

    and_: str = "min"
    or_: str = "max"
    implication: str = "min"
    aggregation: str = "max"


@dataclass(frozen=True, slots=True)
class RuleTable:
    """Says the rules were written as a table: ``rows`` x ``columns`` -> ``output``.

    Only a presentation hint (for ``info`` and for writing YAML back in table form); the rules
    themselves are always in ``RuleBase.rules``, row-major, empty cells skipped.
    """

    rows: str
    columns: str
    output: str


@dataclass(frozen=True, slots=True)
class Source:
    """Where a model was loaded from: a path (or ``<string>``) and the sha256 of its text."""

    path: str
    sha256: str


@dataclass(frozen=True, slots=True)
class RuleBase(NotebookDisplay):
    """A complete rule base: Mamdani outputs, Sugeno outputs (``constant``/``linear`` terms), or
    both. Displayed as tables in notebooks (see NotebookDisplay).

    ``coverage`` (see COVERAGE_POLICIES) says whether an input range that no term covers is an
    error or a warning; importers of foreign formats set ``allow_gaps``.
    """

    name: str
    inputs: tuple[Variable, ...]
    outputs: tuple[Variable, ...]
    rules: tuple[Rule, ...]
    operators: Operators = Operators()
    defuzzifier: str = "centroid"
    out_of_range: str = "clamp"
    description: str = ""
    table: RuleTable | None = None
    source: Source | None = field(default=None, compare=False)
    coverage: str = "strict"

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.inputs)

    @property
    def output_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.outputs)

    def input(self, name: str) -> Variable:
        for v in self.inputs:
            if v.name == name:
                return v
        raise KeyError(name)

    def output(self, name: str) -> Variable:
        for v in self.outputs:
            if v.name == name:
                return v
        raise KeyError(name)

    def variable(self, name: str) -> Variable:
        for v in self.inputs + self.outputs:
            if v.name == name:
                return v
        raise KeyError(name)
