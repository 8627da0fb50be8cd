"""The spelling of a user's name in generated code: reserved words mangled, never refused.

Names are the user's (issue 29 item 6): a rule base, variable or term may be called ``in``,
``class`` or ``int`` in every format that accepts it. Only the rule base's name becomes an
identifier in generated code (the C symbol prefix, the C and Python file and module names);
variable and term names appear there only in strings and comments. :func:`symbol` is the
deterministic mangling, and :func:`names_note` the sentence every generated header carries
when it applied.
"""

from __future__ import annotations

from fuzzkit.codegen.target import all_targets
from fuzzkit.fuzzy.validation import C_KEYWORDS, PYTHON_KEYWORDS

#: Prepended to a name C reserves for the implementation (a leading ``__`` or ``_`` + capital).
RESERVED_PREFIX_FIX = "fk"


def _c_reserved_prefix(name: str) -> bool:
    return name.startswith("__") or (len(name) > 1 and name[0] == "_" and name[1].isupper())


def _reserved(name: str) -> bool:
    return (
        name in C_KEYWORDS
        or name in PYTHON_KEYWORDS
        or any(name in t.reserved_words for t in all_targets())
    )


def symbol(name: str) -> str:
    """``name`` as generated code spells it: unchanged unless a target language reserves it.

    A keyword or reserved word of any target (``in``, ``int``, ``None``) gets a trailing ``_``
    (``in_``), repeated until the result is free; a name C reserves for the implementation
    (``__x``, ``_Foo``) gets the prefix :data:`RESERVED_PREFIX_FIX` (``fk__x``, ``fk_Foo``).

    Examples
    --------
    >>> symbol("in"), symbol("e1"), symbol("_Bool")
    ('in_', 'e1', 'fk_Bool')
    """
    out = RESERVED_PREFIX_FIX + name if _c_reserved_prefix(name) else name
    while _reserved(out):
        out += "_"
    return out


def names_note(rb_name: str) -> str:
    """The header's sentence saying how the rule base's name was spelt, or "" if unchanged."""
    spelt = symbol(rb_name)
    if spelt == rb_name:
        return ""
    return (
        f"Names: rule base {rb_name!r} is spelt {spelt!r} in this code (symbols, files, "
        "module), as it is reserved in C or Python (fuzzkit appends '_', or prefixes "
        f"'{RESERVED_PREFIX_FIX}' to a leading '__' or '_' + capital)."
    )
