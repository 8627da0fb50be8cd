"""Notebook display of a rule base: the mixin behind ``RuleBase._repr_markdown_`` / ``_repr_html_``.

Kept apart from :mod:`fuzzkit.fuzzy.model` so the model stays a plain record: the model mixes
this in, and the text comes from :mod:`fuzzkit.fuzzy.describe`, which formats from the model's
fields only (imported on first display, as describe itself imports the model).
"""

from __future__ import annotations


class NotebookDisplay:
    """Mixin giving a rule base a readable display in Jupyter (Markdown and HTML)."""

    __slots__ = ()

    def _repr_markdown_(self) -> str:
        """Variables with ranges, units and terms, the operators, and the rules (a table)."""
        from fuzzkit.fuzzy.describe import to_markdown
        from fuzzkit.fuzzy.model import RuleBase

        if not isinstance(self, RuleBase):
            raise TypeError(f"NotebookDisplay is for RuleBase, not {type(self).__name__}")
        return to_markdown(self)

    def _repr_html_(self) -> str:
        """The same content as :meth:`_repr_markdown_` as an HTML fragment."""
        from fuzzkit.fuzzy.describe import to_html
        from fuzzkit.fuzzy.model import RuleBase

        if not isinstance(self, RuleBase):
            raise TypeError(f"NotebookDisplay is for RuleBase, not {type(self).__name__}")
        return to_html(self)
