"""The spelling of a user's name in generated code: reserved words mangled, never refused.

Names are the user's (issue 29 item 6): a rule base, variable or term may be called ``in``,
``class`` or ``int`` in every format that accepts it. Only the rule base's name becomes an
identifier in generated code (the C symbol prefix, the C and Python file and module names);
variable and term names appear there only in strings and comments. :func:`symbol` is the
deterministic mangling, and :func:`names_note` the sentence every generated header carries
when it applied.

The mangling is injective (issue 40 item 7): two rule bases never get the same files or
symbols. Each escape also applies to the ordinary names that look like its output, so no
output is shared: ``in`` becomes ``in_``, and ``in_`` therefore ``in__``; ``_X`` becomes
``fk_X``, and ``fk_X`` therefore ``fkfk_X``. Names that look like neither escape are kept.
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


def _needs_prefix(name: str) -> bool:
    # with every leading "fk" removed: a C-reserved start, or underscores only (a bare "_"
    # is Python's soft keyword, and "_" + "_" would be C-reserved)
    core = name
    while core.startswith(RESERVED_PREFIX_FIX):
        core = core[len(RESERVED_PREFIX_FIX) :]
    return _c_reserved_prefix(core) or (core != "" and core.strip("_") == "")


def _needs_suffix(name: str) -> bool:
    # the name without its trailing underscores is reserved (``in``, ``in_``, ``in__``)
    return _reserved(name.rstrip("_"))


def symbol(name: str) -> str:
    """``name`` as generated code spells it: unchanged unless a target language reserves it.

    Two steps, each one-to-one, so the whole is: a name that, with its leading ``fk``\\ s
    removed, starts as C reserves for the implementation (``__x``, ``_Foo``, also ``fk_Foo``)
    or is all underscores gets the prefix :data:`RESERVED_PREFIX_FIX` (``fk__x``, ``fk_Foo``,
    ``fkfk_Foo``); then a name that, with its trailing ``_``\\ s removed, is a keyword or
    reserved word of a target (``in``, ``in_``) gets one more ``_`` (``in_``, ``in__``).

    Examples
    --------
    >>> symbol("in"), symbol("in_"), symbol("e1"), symbol("_Bool"), symbol("fk_Bool")
    ('in_', 'in__', 'e1', 'fk_Bool', 'fkfk_Bool')
    """
    out = RESERVED_PREFIX_FIX + name if _needs_prefix(name) else name
    return out + "_" if _needs_suffix(out) else out


def names_note(rb_name: str) -> str:
    """The header's sentence saying how the rule base's name was spelt, or "" if unchanged."""
    spelt = symbol(rb_name)
    if spelt == rb_name:
        return ""
    return (
        f"Names: rule base {rb_name!r} is spelt {spelt!r} in this code (symbols, files, "
        "module), as it is reserved in C or Python or looks like such a spelling (fuzzkit "
        f"appends '_' to a reserved word and its '_' spellings, and prefixes "
        f"'{RESERVED_PREFIX_FIX}' to a leading '__' or '_' + capital and its "
        f"'{RESERVED_PREFIX_FIX}' spellings)."
    )
