"""The foreign rule-base formats are one table (fuzzkit.formats.registry.FORMATS): every
command that reads, writes, recognises or offers a format goes by it."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.cli import interop
from fuzzkit.cli.file_kinds import recognise
from fuzzkit.formats import fcl, fis, fll, registry
from fuzzkit.fuzzy import shapes


def test_cli_format_choices_are_the_table() -> None:
    assert interop.FORMAT_NAMES == registry.EXPORT_FORMATS == tuple(registry.FORMATS)


@pytest.mark.parametrize("module", [fis, fcl, fll], ids=lambda m: m.__name__.rsplit(".", 1)[1])
def test_each_format_module_is_in_the_table(module: object) -> None:
    fmt = module.FORMAT  # type: ignore[attr-defined]
    assert registry.FORMATS[fmt.name] is fmt
    assert fmt.suffix == module.SUFFIX  # type: ignore[attr-defined]
    assert registry.READERS[fmt.suffix] is fmt.read
    assert fmt.suffix in registry.RULEBASE_SUFFIXES
    assert shapes.spellings(fmt.name)  # the shape registry spells every shape for it


@pytest.mark.parametrize("name", list(registry.FORMATS))
def test_written_text_is_recognised_and_read_back(name: str, tmp_path: Path) -> None:
    """Export a shipped rule base through the table, then `fuzzkit validate`'s recogniser
    finds the format by its first word even under a foreign extension, and reads it back."""
    rb = registry.load("macvicar_whelan")
    fmt = registry.FORMATS[name]
    path = tmp_path / "rules.txt"
    path.write_text(registry.dumps(rb, name, allow_loss=True), encoding="utf-8")
    kind, suffix = recognise(str(path))
    assert (kind.name, suffix) == ("rule base", fmt.suffix)
    back, _ = fmt.read(path)
    assert [r.consequents for r in back.rules] == [r.consequents for r in rb.rules]


def test_unknown_format_and_dialect_are_refused() -> None:
    rb = registry.load("macvicar_whelan")
    with pytest.raises(ValueError, match="unknown format 'xml'"):
        registry.dumps(rb, "xml")
    with pytest.raises(ValueError, match="unknown FCL dialect 'nope'"):
        registry.dumps(rb, "fcl", dialect="nope")
