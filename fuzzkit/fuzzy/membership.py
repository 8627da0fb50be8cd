"""Membership evaluation for the engine: terms of the model through the shape registry.

The formulas, parameter checks, supports and centres of the shapes live in
:mod:`fuzzkit.fuzzy.shapes` (one record per shape); this module applies them to
:class:`~fuzzkit.fuzzy.model.Term` objects. A term whose shape is not registered raises
:class:`~fuzzkit.fuzzy.shapes.UnknownShapeError` here instead of being taken for another shape.

The piecewise-linear shapes (triangle, trapezoid, shoulders) are also available as a vertex list
(:func:`breakpoints`) and a trapezoid form (:func:`trapezoid_form`) from which the exact engine
integrates in closed form.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.model import Term
from fuzzkit.fuzzy.shapes import FloatArray, shape

#: Under ``out_of_range: extend`` every engine (type-1 and Sugeno batch and scalar paths, the
#: IT2 kernel) and the generated double code bound an input to +-this, so that no product of
#: inputs, coefficients and memberships overflows.
EXTEND_LIMIT = 1e100


def evaluate_term(term: Term, x: npt.ArrayLike) -> FloatArray:
    """Membership of ``x`` (any shape) in ``term``.

    Raises
    ------
    ValueError
        For a Sugeno term (``constant``, ``linear``): it is an output value, not a membership
        function (see :func:`sugeno_value`); UnknownShapeError (a ValueError) for a shape
        that is not registered.
    """
    record = shape(term.shape)
    if record.mu is None:
        raise ValueError(
            f"term {term.name!r}: {term.shape} is a Sugeno output term, not a membership function"
        )
    return record.mu(np.asarray(x, dtype=np.float64), *term.params)


def sugeno_value(term: Term, inputs: Sequence[FloatArray]) -> FloatArray:
    """The output value of a Sugeno term at the given input values (arrays of one shape).

    ``constant``: its value everywhere. ``linear``: ``c_1 x_1 + ... + c_n x_n + constant`` with
    ``inputs`` in the rule base's input order. NaN in a used input gives NaN.
    """
    if term.shape == "constant":
        return np.full(np.shape(inputs[0]) if inputs else (), term.params[0])
    if term.shape == "linear":
        z = np.full(np.shape(inputs[0]) if inputs else (), term.params[-1])
        for c, x in zip(term.params[:-1], inputs, strict=True):
            if c != 0.0:
                z = z + c * x
        return z
    raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not a Sugeno term")


def trapezoid_form(term: Term) -> tuple[float, float, float, float]:
    """A piecewise-linear term as ``(core_start, core_end, rise_slope, fall_slope)``.

    ``mu = clip(min(1 + (x - core_start) rise, 1 + (core_end - x) fall), 0, 1)``; a shoulder's
    open side has slope 0. This is how the engine fuzzifies all piecewise-linear terms at once.
    """
    form = shape(term.shape).trapezoid
    if form is None:
        raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not piecewise linear")
    return form(term.params)


def breakpoints(term: Term) -> tuple[float, ...]:
    """The x positions where a piecewise-linear term changes slope (its vertices)."""
    points = shape(term.shape).points
    if points is None:
        raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not piecewise linear")
    return tuple(x for x, _ in points(term.params))


def centre(term: Term, low: float, high: float) -> float:
    """Representative value of a term for the weighted-average defuzzifier (paper eq. 10).

    The midpoint of the set of points of ``[low, high]`` where the term reaches its largest
    membership: the peak of a triangle, the middle of a trapezoid's core, the middle of a
    shoulder's core within the range, the mean of a gaussian or bell (clamped to the range),
    the range end a sigmoid opens towards, a singleton's value. The smooth MATLAB shapes follow
    the same rule (the difference and product of sigmoids on a grid of 65537 points). Each
    shape's rule is its registry record's ``centre``.

    Raises
    ------
    ValueError
        For a Sugeno term, and (UnknownShapeError) for a shape that is not registered.
    """
    rule = shape(term.shape).centre
    if rule is None:
        raise ValueError(f"term {term.name!r}: {term.shape} is a Sugeno output term; no centre")
    return rule(term.params, low, high)
