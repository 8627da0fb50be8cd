"""The fuzzy core: the frozen rule-base model, membership shapes, semantic checks, the exact engine.

Imports nothing else of fuzzkit but :mod:`fuzzkit.errors` (the bottom layer; checked by
``lint-imports``).
"""

# The notebook display of RuleBase formats with fuzzkit.fuzzy.describe, which registers itself.
from fuzzkit.fuzzy import describe as _describe  # noqa: F401
