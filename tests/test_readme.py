"""The README says what the code does: its API tour runs as written, its codegen claims match
the generated headers."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parent.parent / "README.md"


def _section(title: str) -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index(f"## {title}")
    end = text.find("\n## ", start + 1)
    return text[start : end if end > 0 else None]


@pytest.mark.slow
def test_the_api_tour_runs_as_written() -> None:
    blocks = re.findall(r"```python\n(.*?)```", _section("A tour of the Python API"), re.S)
    assert blocks, "the API tour has no python block"
    namespace: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, str(README), "exec"), namespace)
    # the values the tour's comments promise
    import fuzzkit

    rb = fuzzkit.load("macvicar_whelan")
    assert "fuzzkit.loads(dump(rb)) == rb" in blocks[0]
    shown = re.search(
        r"evaluate_point\(rb, e=0.3, de=-0.2\)\s+# \{'du': ([0-9.]+)\.\.\.\}", blocks[0]
    )
    assert shown is not None
    du = fuzzkit.evaluate_point(rb, e=0.3, de=-0.2)["du"]
    assert f"{du:.16f}".startswith(shown.group(1))
    assert namespace["du"].shape == (101, 101)  # type: ignore[attr-defined]


def test_codegen_claims_match_the_generated_header() -> None:
    from fuzzkit.codegen.emit import emit
    from fuzzkit.codegen.table_search import make_table
    from fuzzkit.formats.registry import load

    claims = " ".join(_section("Code generation").split())
    grid = re.search(r"on a grid (\d+)x denser than the table", claims)
    margin = re.search(r"A (\d+) % margin is added", claims)
    refine = re.search(r"resampled (\d+)x per axis", claims)
    assert grid and margin and refine, "the README no longer states how the bound is measured"

    rb = load("macvicar_whelan")
    table = make_table(rb)  # the default tolerance, as the README's figures
    header = " ".join(emit(rb, table, "c")["macvicar_whelan.h"].replace(" * ", " ").split())
    assert f"a grid {grid.group(1)}x denser than the table" in header
    assert f"+ {margin.group(1)} % for the points between them" in header
    assert f"resampled {refine.group(1)}x per axis" in header
    # and the header's bound is what the code computes: the maximum times the margin,
    # rounded up to 3 significant digits (never down, never by more than one unit)
    (bound,) = table.bound
    (measured,) = table.measured
    scaled = measured * (1 + int(margin.group(1)) / 100)
    assert scaled <= bound <= scaled * (1 + 1e-2)
    assert f"du: {bound:g}" in header
