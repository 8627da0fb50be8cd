"""The rounding bound the exact-method units state (type-1, ``codegen.exact``, and interval
type-2, ``codegen.exact_type2``), and the number types they compute in: defined once."""

from __future__ import annotations

#: Number types the exact target computes in (Q15 has no exact inference: use a table).
EXACT_NUMBER_TYPES = ("float", "double")

#: Stated bound of |generated - exact engine| for the continuous defuzzifiers (centroid,
#: bisector, weighted average) as a multiple of the number type's machine epsilon times the
#: output's full scale (largest |range end|): 2^-52 S x 64 for double (Python too), 2^-23 S x 64
#: for float. Tested on 1e5 random points plus edges for every shipped rule base and a random
#: family; see codegen/README.md. mom/som/lom are discontinuous where two maxima tie: the
#: bound holds away from ties (double: levels within 1e-10 of each other count as tied, as in
#: the engine); at a tie a rounding difference can move the result to the other maximum.
ROUNDING_ULPS = 256
EPSILON = {"double": 2.0**-52, "float": 2.0**-23}
ROUNDING_BOUND = {k: ROUNDING_ULPS * v for k, v in EPSILON.items()}

__all__ = ["EPSILON", "EXACT_NUMBER_TYPES", "ROUNDING_BOUND", "ROUNDING_ULPS"]
