"""The footprint of uncertainty of an interval type-2 (IT2) rule base, beside the type-1 model.

An IT2 rule base is a :class:`Type2RuleBase`: a :class:`~fuzzkit.fuzzy.model.RuleBase` with a
``footprint``. Its variables' terms are the **upper** membership functions (so every type-1
tool that draws or lists terms sees the upper ones); the footprint adds, per IT2 term, the
**lower** membership function: a type-1 shape times a height ``scale`` in (0, 1]. A term the
footprint does not list is type-1 inside the IT2 system (its lower function equals its upper
one). The footprint also names the type reduction and, optionally, MATLAB's discretised output
universe.

Semantics: docs/type2.md; the engine: :mod:`fuzzkit.fuzzy.type2_inference`; the type
reduction: :mod:`fuzzkit.fuzzy.type_reduction`; the checks: :mod:`fuzzkit.fuzzy.type2_validation`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from fuzzkit.fuzzy.model import RuleBase, Term, Variable

#: Type-reduction methods: Karnik-Mendel (exact interval), enhanced KM (the same interval, the
#: name MATLAB and pyit2fls use for the faster iteration), Nie-Tan (closed-form average of the
#: upper and lower sets) and Wu-Mendel (the midpoint of the uncertainty bounds).
TYPE_REDUCTIONS = ("karnik-mendel", "ekm", "nie-tan", "wu-mendel")
DEFAULT_TYPE_REDUCTION = "karnik-mendel"
#: Largest discretised output universe (MATLAB's ``OutputSamplePoints`` default is 101).
MAX_RESOLUTION = 100_001


@dataclass(frozen=True, slots=True)
class LowerTerm:
    """The lower membership function of the IT2 term ``variable.term``: ``scale * shape(x)``.

    ``shape`` is a type-1 term (its name is the IT2 term's name) of any membership shape.
    """

    variable: str
    term: str
    shape: Term
    scale: float = 1.0


@dataclass(frozen=True, slots=True)
class Footprint:
    """The IT2 part of a rule base: lower functions, type reduction, output discretisation.

    ``resolution`` ``None`` (default) type-reduces on the continuous output universe, exactly;
    an integer ``N`` samples each output range at ``N`` evenly spaced points first (MATLAB's
    ``OutputSamplePoints``, pyit2fls's domain) and type-reduces the samples.
    """

    lowers: tuple[LowerTerm, ...] = ()
    type_reduction: str = DEFAULT_TYPE_REDUCTION
    resolution: int | None = None

    def lower(self, variable: str, term: str) -> LowerTerm | None:
        """The lower function of ``variable.term``; ``None`` when that term is type-1."""
        for lt in self.lowers:
            if lt.variable == variable and lt.term == term:
                return lt
        return None

    def lower_terms(self, var: Variable) -> tuple[tuple[Term, ...], tuple[float, ...]]:
        """The lower shapes of ``var``'s terms (the upper one for a type-1 term) and heights."""
        shapes: list[Term] = []
        scales: list[float] = []
        for t in var.terms:
            lt = self.lower(var.name, t.name)
            shapes.append(t if lt is None else lt.shape)
            scales.append(1.0 if lt is None else lt.scale)
        return tuple(shapes), tuple(scales)


@dataclass(frozen=True, slots=True)
class Type2RuleBase(RuleBase):
    """An interval type-2 rule base: the type-1 fields hold the upper terms, ``footprint``
    the lower ones and the type reduction. Every type-1 tool reads it as a rule base; the
    engine (``fuzzy.inference.Engine``) evaluates it as IT2."""

    footprint: Footprint = Footprint()


def footprint_of(rb: RuleBase) -> Footprint | None:
    """The footprint of an IT2 rule base; ``None`` for a type-1 one."""
    return rb.footprint if isinstance(rb, Type2RuleBase) else None


def with_footprint(rb: RuleBase, footprint: Footprint) -> Type2RuleBase:
    """``rb`` (its terms the upper ones) made interval type-2 with ``footprint``."""
    kept = {f.name: getattr(rb, f.name) for f in fields(RuleBase)}
    return Type2RuleBase(**kept, footprint=footprint)
