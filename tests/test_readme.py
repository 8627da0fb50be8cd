"""The README and docs/ say what the code does: the API tour runs as written, the codegen
claims match the generated headers, every command of every page runs, links stay inside the
repository."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parent.parent / "README.md"
COMPILE = README.parent / "docs" / "compile.md"


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

    claims = " ".join(COMPILE.read_text(encoding="utf-8").split())
    grid = re.search(r"on a grid (\d+)x denser than the table", claims)
    margin = re.search(r"A (\d+) % margin is added", claims)
    refine = re.search(r"resampled (\d+)x per axis", claims)
    assert grid and margin and refine, "docs/compile.md no longer states how the bound is measured"

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


# --------------------------------------------------------------------------- every command


def _pages_with_commands() -> list[Path]:
    from tests._doc_commands import PAGES, commands

    return [p for p in PAGES if commands(p)]


def test_every_command_is_run_or_says_why_not() -> None:
    """A command block holds only commands the docs test runs, or ones it names a reason for."""
    from tests._doc_commands import PAGES, commands, not_run_reason

    found = [c for p in PAGES for c in commands(p)]
    assert len(found) > 30
    strays = [
        f"{c.where}: {c.text}"
        for c in found
        if not c.text.startswith("fuzzkit ") and not_run_reason(c.text) is None
    ]
    assert not strays, "commands neither run nor explained (tests/_doc_commands.py NOT_RUN)"


@pytest.mark.slow
@pytest.mark.parametrize("page", _pages_with_commands(), ids=lambda p: p.name)
def test_the_commands_of_the_page_run_as_written(page: Path, tmp_path: Path) -> None:
    """Every ``fuzzkit`` command of the page's ``sh`` blocks, in order, in a scratch folder
    holding copies of what they read; slow ones with smaller budgets (``LIMITS``)."""
    import os
    import subprocess
    import sys

    from tests._doc_commands import commands, limited, not_run_reason, workspace

    workspace(tmp_path)
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    ran = 0
    for cmd in commands(page):
        if not_run_reason(cmd.text) is not None:
            continue
        shell = limited(cmd.text)
        res = subprocess.run(
            shell, shell=True, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600
        )
        assert res.returncode == 0, (
            f"{cmd.where}: {shell}\n{res.stdout[-2000:]}{res.stderr[-3000:]}"
        )
        ran += 1
    assert ran > 0


def _anchors(page: Path) -> set[str]:
    """The anchors of a Markdown page's headings, as GitHub makes them."""
    out = set()
    for title in re.findall(r"^#+ (.*)$", page.read_text(encoding="utf-8"), re.M):
        slug = re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")
        out.add(slug)
    return out


def test_no_page_refers_outside_the_repository() -> None:
    """Links resolve to files in the repository; no page names the authors' working files."""
    from tests._doc_commands import PAGES, ROOT

    problems = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for word in ("DESIGN.md", "STYLE.md", "/work/"):
            if word in text:
                problems.append(f"{page.name}: mentions {word}")
        for target, anchor in re.findall(r"\]\(([^)#\s]*)(?:#([^)\s]*))?\)", text):
            if "://" in target or target.startswith("mailto:"):
                continue
            resolved = (page.parent / target).resolve() if target else page
            if not resolved.is_relative_to(ROOT) or not resolved.exists():
                problems.append(f"{page.name}: link to {target}")
            elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
                problems.append(f"{page.name}: link to {target}#{anchor}: no such heading")
    assert not problems, problems


def test_the_shipped_rule_base_list_is_complete() -> None:
    from fuzzkit.formats.registry import available

    text = (README.parent / "docs" / "rulebase-format.md").read_text(encoding="utf-8")
    section = text[text.index("## Shipped rule bases") :]
    section = section[: section.find("\n## ", 5) if "\n## " in section[5:] else None]
    listed = re.findall(r"^\| `([a-z0-9_]+)` \|", section, re.M)
    assert sorted(listed) == sorted(available())
