"""The README and docs/ say what the code does: the API tour runs as written, the codegen
claims match the generated headers, every command of every page runs, links stay inside the
repository."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from tests._doc_commands import PAGES, commands, limited, not_run_reason, workspace
from tests._doc_plan import Group, keys, plan, words
from tests._doc_run import run_group, run_in_process, run_in_shell

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


GROUPS = plan()


def test_every_command_is_run_or_says_why_not() -> None:
    """A command block holds only commands the docs test runs, or ones it names a reason for."""
    found = [c for p in PAGES for c in commands(p)]
    assert len(found) > 30
    strays = [
        f"{c.where}: {c.text}"
        for c in found
        if not c.text.startswith("fuzzkit ") and not_run_reason(c.text) is None
    ]
    assert not strays, "commands neither run nor explained (tests/_doc_commands.py NOT_RUN)"


def test_every_command_found_is_run_once() -> None:
    """The groups run every place of every command the pages show (less ``NOT_RUN``), each
    distinct command once, and each place's command as that page limits it."""
    found = sorted(
        (c.where, limited(c.text))
        for p in PAGES
        for c in commands(p)
        if not_run_reason(c.text) is None
    )
    steps = [step for group in GROUPS for step in group.steps]
    assert sorted((place.where, s.text) for s in steps for place in s.places) == found
    assert len({s.key for s in steps}) == len(steps), "a command runs twice"
    assert len({group.id for group in GROUPS}) == len(GROUPS)


def test_each_group_runs_what_its_commands_need() -> None:
    """A command that names a file an earlier command of its page writes runs after that
    command, in its group; every command of a group keeps its page's key there."""
    for group in GROUPS:
        texts = [s.text for s in group.steps]
        assert keys(texts) == [s.key for s in group.steps], group.id


@pytest.fixture(scope="session")
def workspace_template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One workspace (tests/_doc_commands.py) per test process, copied for every group."""
    folder = tmp_path_factory.mktemp("doc-workspace")
    workspace(folder)
    return folder


@pytest.mark.slow
@pytest.mark.parametrize("group", GROUPS, ids=lambda g: g.id)
def test_the_commands_of_the_docs_run_as_written(
    group: Group, workspace_template: Path, tmp_path: Path
) -> None:
    """Every ``fuzzkit`` command of the pages' ``sh`` blocks, once, with the earlier commands
    of its page it needs, in a scratch folder holding copies of what they read; slow ones
    with smaller budgets (``LIMITS``)."""
    shutil.copytree(workspace_template, tmp_path, dirs_exist_ok=True)
    failures = run_group(group, tmp_path)
    assert not failures, "\n\n".join(failures)


# --------------------------------------------------------------------------- the plan, the runs


def _page(folder: Path, name: str, *lines: str) -> Path:
    page = folder / name
    page.write_text("# a page\n\n```sh\n" + "\n".join(lines) + "\n```\n", encoding="utf-8")
    return page


def test_a_command_runs_with_the_ones_that_write_what_it_names(tmp_path: Path) -> None:
    a = _page(
        tmp_path,
        "a.md",
        "fuzzkit import tank.fis --out tank.yaml",  # line 4
        "fuzzkit info macvicar_whelan",
        "fuzzkit export tank.yaml --format fll --out tank.fll",
        "fuzzkit schema > s.json",
        "fuzzkit validate s.json tank.fll",  # reads what 6 and 7 wrote: 4, 6, 7 and 8 are one
        "fuzzkit compile macvicar_whelan --target c --out gen/",
        "fuzzkit compile macvicar_whelan --target python --out gen",  # writes 9's folder again
    )
    b = _page(
        tmp_path,
        "b.md",
        "fuzzkit info macvicar_whelan",  # a's line 5: runs once
        "fuzzkit export tank.yaml --format fll --out tank.fll",  # no import before it here
        "fuzzkit compile macvicar_whelan --target c --out gen/",  # a's line 9, and then 10
        "fuzzkit validate other.yaml",
    )
    groups = plan([a, b])
    assert [(g.id, [s.where for s in g.steps]) for g in groups] == [
        ("a.md:4-import+3", ["a.md:4", "a.md:6", "a.md:7", "a.md:8"]),
        ("a.md:5-info", ["a.md:5, b.md:4"]),
        ("a.md:9-compile+1", ["a.md:9, b.md:6", "a.md:10"]),
        ("b.md:5-export", ["b.md:5"]),
        ("b.md:7-validate", ["b.md:7"]),
    ]


def test_a_shared_command_is_not_run_again_for_another_page(tmp_path: Path) -> None:
    first = "fuzzkit import tank.fis --out t.yaml"
    a = _page(tmp_path, "a.md", first, "fuzzkit export t.yaml --format fll --out x.fll")
    b = _page(tmp_path, "b.md", first, "fuzzkit info t.yaml")
    c = _page(tmp_path, "c.md", first, "fuzzkit export t.yaml --format fcl --out x.fll")
    # b's info joins a's group (it names nothing a's export writes); c's export writes what
    # a's export writes, so after it, it would write into a's file: c's group runs on its own
    assert [[s.where for s in g.steps] for g in plan([a, b, c])] == [
        ["a.md:4, b.md:4, c.md:4", "a.md:5", "b.md:5"],
        ["a.md:4, b.md:4, c.md:4", "c.md:5"],
    ]


def test_a_failing_command_is_reported_at_every_place_it_appears(
    workspace_template: Path, tmp_path: Path
) -> None:
    pages = [
        _page(tmp_path, "a.md", "fuzzkit info macvicar_whelan --no-such-option"),
        _page(tmp_path, "b.md", "fuzzkit validate my_rules.yaml", "fuzzkit schema --nope > x"),
        _page(tmp_path, "c.md", "fuzzkit info macvicar_whelan --no-such-option"),
    ]
    shutil.copytree(workspace_template, tmp_path / "w")
    failures = [f for group in plan(pages) for f in run_group(group, tmp_path / "w")]
    assert len(failures) == 2, failures
    assert failures[0].startswith("a.md:4, c.md:4: fuzzkit info macvicar_whelan --no-such")
    assert "exit 2" in failures[0] and "unrecognized arguments: --no-such-option" in failures[0]
    assert failures[1].startswith("b.md:5: fuzzkit schema --nope > x\nexit 2")


def test_a_file_written_behind_the_plans_back_is_reported(
    workspace_template: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import tests._doc_plan

    monkeypatch.setattr(
        tests._doc_plan, "OUTPUT_OPTIONS", tests._doc_plan.OUTPUT_OPTIONS - {"--out"}
    )
    page = _page(tmp_path, "a.md", "fuzzkit export macvicar_whelan --format fll --out mw.fll")
    shutil.copytree(workspace_template, tmp_path / "w")
    (group,) = plan([page])
    assert run_group(group, tmp_path / "w") == [
        "a.md:4: fuzzkit export macvicar_whelan --format fll --out mw.fll\nwrote mw.fll, which "
        "none of its output options names (tests/_doc_plan.py OUTPUT_OPTIONS)"
    ]


def test_a_file_read_behind_the_plans_back_is_reported(
    workspace_template: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import fuzzkit.cli.rulebase

    def info_that_reads_x_fll(args: object) -> int:
        with contextlib.suppress(FileNotFoundError):
            Path("x.fll").read_text()
        return 0

    monkeypatch.setattr(fuzzkit.cli.rulebase, "cmd_info", info_that_reads_x_fll)
    page = _page(
        tmp_path,
        "a.md",
        "fuzzkit export macvicar_whelan --format fll --out x.fll",
        "fuzzkit info macvicar_whelan",
    )
    shutil.copytree(workspace_template, tmp_path / "w")
    _export, info = plan([page])
    assert run_group(info, tmp_path / "w") == [
        "a.md:5: fuzzkit info macvicar_whelan\nread x.fll, which an earlier command of its "
        "page writes, without naming it (tests/_doc_plan.py)"
    ]


@pytest.mark.parametrize(
    "command",
    [
        "fuzzkit info macvicar_whelan",
        "fuzzkit eval macvicar_whelan -i e=0.3 -i de=-0.2 --json",
        "fuzzkit info no_such_rule_base",  # the user's error: exit 2, no traceback
        "fuzzkit eval macvicar_whelan --no-such-option",  # argparse's SystemExit(2)
        "fuzzkit validate --help",  # SystemExit(0)
    ],
)
def test_a_command_in_process_does_what_the_fuzzkit_process_does(
    command: str, workspace_template: Path
) -> None:
    """Exit code, stdout and stderr as the console script's (the independent reference: a
    fresh process); and the test's own process as it was before."""
    state = (os.getcwd(), dict(os.environ), sys.argv[:], warnings.filters[:])
    sigint = signal.getsignal(signal.SIGINT)
    ours = run_in_process(words(command)[1:], workspace_template)
    assert (os.getcwd(), dict(os.environ), sys.argv, warnings.filters) == state
    assert signal.getsignal(signal.SIGINT) is sigint
    theirs = run_in_shell(command, workspace_template)
    assert (ours.code, ours.stdout, ours.stderr) == (theirs.code, theirs.stdout, theirs.stderr)


def test_a_command_in_process_runs_under_a_fresh_interpreters_warning_filters(
    workspace_template: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """pytest's filters (pyproject.toml turns fuzzkit's RuntimeWarnings into errors) are not
    the ones a user's ``fuzzkit`` runs under."""
    import fuzzkit.cli.rulebase

    seen: list[object] = []
    monkeypatch.setattr(
        fuzzkit.cli.rulebase, "cmd_info", lambda args: seen.append(eval(_FILTERS, {"w": warnings}))
    )
    assert run_in_process(["info", "macvicar_whelan"], workspace_template).code == 0
    fresh = subprocess.run(
        [sys.executable, "-c", f"import json, warnings as w; print(json.dumps({_FILTERS}))"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(json.dumps(seen)) == [json.loads(fresh.stdout)]


#: The warning filters, comparable across processes: classes by name, regexes as patterns.
_FILTERS = (
    "[(a, getattr(m, 'pattern', m), c.__name__, getattr(d, 'pattern', d), n)"
    " for a, m, c, d, n in w.filters]"
)


@pytest.mark.slow
def test_a_second_command_in_process_reads_the_file_as_it_is_now(
    workspace_template: Path, tmp_path: Path
) -> None:
    """fuzzkit caches rule bases by their path: a second command in the same process must see
    a rewritten file, as a second ``fuzzkit`` process does."""

    # the reference controller's exact surface is cached by the rule base's path
    argv = ["simulate", "E1", "--rulebase", "rb.yaml", "--controller-impl", "reference", "--json"]

    def simulate() -> dict[str, object]:
        done = run_in_process(argv, tmp_path)
        assert done.code == 0, done.stderr
        return _without_timings(json.loads(done.stdout))

    shutil.copytree(workspace_template, tmp_path, dirs_exist_ok=True)
    shutil.copy(tmp_path / "rulebases" / "macvicar_whelan.yaml", tmp_path / "rb.yaml")
    first = simulate()
    shutil.copy(tmp_path / "rulebases" / "paper_table1.yaml", tmp_path / "rb.yaml")
    second = simulate()
    fresh = run_in_shell(f"fuzzkit {' '.join(argv)}", tmp_path)
    assert second == _without_timings(json.loads(fresh.stdout))
    assert second != first


def _without_timings(run: dict[str, object]) -> dict[str, object]:
    return {
        k: v for k, v in run.items() if k not in ("wall_time_s", "cpu_time_s", "real_time_factor")
    }


def _anchors(page: Path) -> set[str]:
    """The anchors of a Markdown page's headings, as GitHub makes them."""
    out = set()
    for title in re.findall(r"^#+ (.*)$", page.read_text(encoding="utf-8"), re.M):
        slug = re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")
        out.add(slug)
    return out


def test_no_page_refers_outside_the_repository() -> None:
    """Links resolve to files in the repository; no page names the authors' working files."""
    from tests._doc_commands import ROOT

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
