"""Notebook display of a rule base: the mixin behind ``RuleBase._repr_markdown_`` / ``_repr_html_``.

Kept apart from :mod:`fuzzkit.fuzzy.model` so the model stays a plain record that knows no
format. The model mixes :class:`NotebookDisplay` in; the text comes from renderers that
:mod:`fuzzkit.fuzzy.describe` registers when it is imported (``fuzzkit.fuzzy`` imports it), which
format from the model's fields only. This module imports nothing of fuzzkit, so the model can
import it without a cycle.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

Renderer = Callable[[Any], str]
_RENDERERS: dict[str, Renderer] = {}


def register_renderer(kind: Literal["markdown", "html"], render: Renderer) -> None:
    """Make ``render(rule_base)`` what a notebook shows as ``kind``."""
    _RENDERERS[kind] = render


class NotebookDisplay:
    """Mixin giving a rule base a readable display in Jupyter (Markdown and HTML)."""

    __slots__ = ()

    def _repr_markdown_(self) -> str | None:
        """Variables with ranges, units and terms, the operators, and the rules (a table)."""
        render = _RENDERERS.get("markdown")
        return render(self) if render is not None else None

    def _repr_html_(self) -> str | None:
        """The same content as :meth:`_repr_markdown_` as an HTML fragment."""
        render = _RENDERERS.get("html")
        return render(self) if render is not None else None
