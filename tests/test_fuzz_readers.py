"""Mutation fuzzing of every reader (issue 25): a damaged file gives a located error, or a
rule base (scenario) that the engine evaluates to finite numbers at its label peaks.

Seeded and bounded: :data:`MUTANTS` per format in ``make verify``, the first
:data:`COVER_MUTANTS` of the same seeded sequence in ``make test``, each given :data:`HUNG_S`
seconds. The
sources are the shipped rule bases, the files of ``docs/examples/`` (and the shipped rule
bases exported to each foreign format) and the shipped scenarios. Warnings are errors
throughout: no ``RuntimeWarning`` may escape."""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import signal
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _mutate import Mutant, keyword_values, mutants, replace_value
from _pairwise import verify

from fuzzkit.control.gains import read_gains_file
from fuzzkit.errors import ConfigError, ProblemsError
from fuzzkit.formats import fcl, fis, fll, registry, yaml_reader
from fuzzkit.formats.foreign_common import ExportError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.plants.robot_description import load_robot
from fuzzkit.studies.scenario_file import SHIPPED, loads_scenario, shipped_scenario_text

ROOT = Path(__file__).resolve().parent.parent
#: Mutants per format in ``make verify``; with the seed, what the test covers (and the issue's
#: closing note).
MUTANTS = 400
SEED = 25
#: Mutants per format in ``make test``: the first of the same sequence (the generator is
#: sequential, so these are a prefix of the verify run), enough that every operator of
#: tests/_mutate.py is drawn for every format several times.
COVER_MUTANTS = 100
#: The mutant count of a fuzz test: the covering count in ``make test``, all in ``make verify``.
COUNTS = [
    pytest.param(COVER_MUTANTS, id="cover"),
    pytest.param(MUTANTS, marks=verify, id="full"),
]
#: Label-peak grids larger than this are sampled (seeded), to bound the time per mutant.
MAX_POINTS = 343

READERS: dict[str, Callable[[str, str], RuleBase]] = {
    "yaml": yaml_reader.loads_rulebase,
    "fis": fis.loads,
    "fcl": fcl.loads,
    "fll": fll.loads,
}


def _sources(fmt: str) -> dict[str, str]:
    shipped = sorted((ROOT / "rulebases").glob("*.yaml"))
    if fmt == "yaml":
        return {p.name: p.read_text() for p in shipped}
    out = {p.name: p.read_text() for p in sorted((ROOT / "docs" / "examples").glob(f"*.{fmt}"))}
    for p in shipped:
        try:
            out[f"{p.stem}.{fmt}"] = registry.dumps(registry.load(p), fmt, allow_loss=True)
        except ExportError:
            continue  # a construct the format cannot hold (e.g. nested conditions in .fis)
    return out


def _peaks(rb: RuleBase) -> dict[str, np.ndarray]:
    axes = [
        sorted({membership.centre(t, v.low, v.high) for t in v.terms} | {v.low, v.high})
        for v in rb.inputs
    ]
    grid = list(itertools.product(*axes))
    if len(grid) > MAX_POINTS:
        pick = np.random.default_rng(SEED).choice(len(grid), MAX_POINTS, replace=False)
        grid = [grid[i] for i in sorted(pick)]
    cols = np.array(grid, dtype=np.float64).reshape(len(grid), len(rb.inputs))
    return {v.name: cols[:, i] for i, v in enumerate(rb.inputs)}


#: A reader that takes longer than this on a mutant of a few kilobytes is taken as hung.
HUNG_S = 30.0


class _Hung(Exception):
    """A mutant took longer than :data:`HUNG_S` (a reader looping over a count, say)."""


@contextlib.contextmanager
def _strict() -> Iterator[None]:
    """Warnings as errors, and :class:`_Hung` after :data:`HUNG_S` seconds."""

    def hung(signum: int, frame: object) -> None:
        raise _Hung(f"no answer within {HUNG_S:g} s")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.setitimer(signal.ITIMER_REAL, HUNG_S)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def _located(exc: ProblemsError, source: str) -> str | None:
    for p in exc.problems:
        if p.location.file != source or p.location.line < 1:
            return f"problem without file:line: {p}"
    return None


def _rule_base_failure(fmt: str, m: Mutant) -> str | None:
    """Why mutant ``m`` breaks the property, or None if it holds."""
    source = f"mutant.{fmt}"
    try:
        with _strict():
            try:
                rb = READERS[fmt](m.text, source)
            except ProblemsError as exc:
                return _located(exc, source)
            values = evaluate(rb, _peaks(rb))
    except Exception as exc:
        return f"{type(exc).__name__}: {str(exc)[:300]}"
    for var in rb.outputs:
        y = values[var.name]
        nan_default = var.default is None or math.isnan(var.default)
        bad = ~np.isfinite(y) & ~(np.isnan(y) & nan_default)
        if bad.any():
            return f"output {var.name!r} is {y[bad][0]} at a label peak"
    return None


@pytest.mark.parametrize("count", COUNTS)
@pytest.mark.parametrize("fmt", sorted(READERS))
def test_mutated_rule_bases_give_located_errors_or_finite_outputs(fmt: str, count: int) -> None:
    sources = _sources(fmt)
    assert len(sources) >= 2
    for origin, text in sources.items():  # compile the engine's kernels outside the timer
        rb = READERS[fmt](text, origin)
        evaluate(rb, _peaks(rb))
    failures = []
    for m in mutants(sources, count, SEED):
        why = _rule_base_failure(fmt, m)
        if why is not None:
            failures.append(f"{m.origin} ({m.what}): {why}")
    assert not failures, f"{len(failures)} of {count} mutants:\n" + "\n".join(failures[:15])


def test_make_tests_mutants_are_the_first_of_make_verifys() -> None:
    """The covering count proves a part of the full run, not other mutants: the same seeded
    sequence, cut short."""
    sources = {f"{name}.yaml": shipped_scenario_text(name) for name in SHIPPED}
    short = list(mutants(sources, COVER_MUTANTS, SEED))
    assert short == list(mutants(sources, MUTANTS, SEED))[:COVER_MUTANTS]
    assert len({m.text for m in short}) > COVER_MUTANTS // 2  # and they differ


@pytest.mark.parametrize("fmt", sorted(READERS))
def test_a_value_replaced_by_any_keyword_of_the_file_gives_a_located_error(fmt: str) -> None:
    """Every ``shape:`` (``type``, ``MF``, ``TERM``...) value of one file of each format, and
    the first value of every other key, replaced by every key the file uses: the class of
    mutant that once reached the defuzzifier check with an unknown shape (issue 29 item 7)."""
    origin, text = sorted(_sources(fmt).items())[0]
    found, keys = keyword_values(text)
    firsts = {m.group(1): m for m in reversed(found)}  # the first value of each key
    shapes = [m for m in found if m.group(1).lower() in ("shape", "type", "mf", "term")]
    targets = list(dict.fromkeys([*shapes, *firsts.values()]))
    assert targets and keys, f"{origin}: no key: value to replace"
    failures = []
    for m in targets:
        for key in keys:
            mutant = Mutant(origin, f"{m.group(1)}: {m.group(2)!r} -> {key!r}", "")
            mutant = dataclasses.replace(mutant, text=replace_value(text, m, key))
            why = _rule_base_failure(fmt, mutant)
            if why is not None:
                failures.append(f"{mutant.what}: {why}")
    assert not failures, f"{len(failures)} mutants:\n" + "\n".join(failures[:15])


def _finite_fields(value: Any) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, tuple | list):
        return all(_finite_fields(v) for v in value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return all(_finite_fields(getattr(value, f.name)) for f in dataclasses.fields(value))
    return True


@pytest.mark.parametrize("count", COUNTS)
def test_mutated_scenarios_give_located_errors_or_finite_experiments(count: int) -> None:
    sources = {f"{name}.yaml": shipped_scenario_text(name) for name in SHIPPED}
    failures = []
    for m in mutants(sources, count, SEED):
        try:
            with _strict():
                exp = loads_scenario(m.text, "mutant.yaml")
        except ProblemsError as exc:
            why = _located(exc, "mutant.yaml")
        except Exception as exc:
            why = f"{type(exc).__name__}: {str(exc)[:300]}"
        else:
            why = None if _finite_fields(exp) else "a non-finite number was accepted"
        if why is not None:
            failures.append(f"{m.origin} ({m.what}): {why}")
    assert not failures, f"{len(failures)} of {count} mutants:\n" + "\n".join(failures[:15])


def _config_failure(load: Callable[[Path], Any], path: Path) -> str | None:
    """Why loading the config file ``path`` breaks the property (located error or finite)."""
    try:
        with _strict():
            loaded = load(path)
    except ConfigError as exc:
        first = str(exc).split("\n")[-1] if "problems found" in str(exc) else str(exc)
        located = first.startswith(f"{path}:") and first[len(str(path)) + 1 :][:1].isdigit()
        return None if located else f"error without file:line: {first[:200]}"
    except Exception as exc:
        return f"{type(exc).__name__}: {str(exc)[:300]}"
    return None if _finite_fields(loaded) else "a non-finite number was accepted"


@pytest.mark.parametrize("count", COUNTS)
@pytest.mark.parametrize("kind", ["gains", "robot"])
def test_mutated_gains_files_and_robot_descriptions_give_located_errors(
    tmp_path: Path, kind: str, count: int
) -> None:
    if kind == "gains":
        folder = ROOT / "docs" / "report" / "gains"
        sources = {p.name: p.read_text() for p in sorted(folder.glob("*.yaml"))}

        def load(path: Path) -> Any:
            return [dataclasses.astuple(e) for e in read_gains_file(path).values()]
    else:
        sources = {"irb140.yaml": (ROOT / "fuzzkit" / "data" / "irb140.yaml").read_text()}
        load = load_robot
    failures = []
    path = tmp_path / "mutant.yaml"
    for m in mutants(sources, count // 2, SEED):
        path.write_text(m.text, encoding="utf-8", errors="surrogatepass")
        why = _config_failure(load, path)
        if why is not None:
            failures.append(f"{m.origin} ({m.what}): {why}")
    assert not failures, f"{len(failures)} of {count // 2}:\n" + "\n".join(failures[:15])


def _stepped_surface(spec: Any) -> Any:
    """The surface a mutant's reference controller steps on: its own for an exact surface
    (None), the exact engine for a table surface (its table, up to 4096 x 4096 breakpoints of
    an IT2 engine, would cost minutes to build; the reader is what is fuzzed here)."""
    from fuzzkit.control.loop_rulebase import exact_surface
    from fuzzkit.control.spec import surface_inputs

    if spec.surface.method != "table" or spec.rulebase is None:
        return None
    return exact_surface(spec.rulebase, surface_inputs(spec, spec.rulebase))


@pytest.mark.parametrize("count", COUNTS)
def test_mutated_controller_specs_give_located_errors_or_working_controllers(count: int) -> None:
    """A damaged controller spec is refused at its place, or it is a valid, finite spec whose
    reference controller steps (the rule base is read relative to the examples)."""
    from fuzzkit.control.reference import Controller
    from fuzzkit.control.spec_reader import loads_spec

    examples = ROOT / "docs" / "examples"
    sources = {p.name: p.read_text() for p in sorted(examples.glob("controller*.yaml"))}
    assert len(sources) >= 4
    down = [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0]
    failures = []
    for m in mutants(sources, count, SEED):
        try:
            with _strict():
                spec = loads_spec(m.text, "mutant.yaml", examples)
                u, _ = Controller(spec, _stepped_surface(spec)).step([0.0, 0.0, 1.0], down)
        except ProblemsError as exc:
            why = _located(exc, "mutant.yaml")
        except Exception as exc:
            why = f"{type(exc).__name__}: {str(exc)[:300]}"
        else:
            finite = _finite_fields(dataclasses.replace(spec, rulebase=None))
            why = None if finite and all(map(math.isfinite, u)) else "non-finite spec or output"
        if why is not None:
            failures.append(f"{m.origin} ({m.what}): {why}")
    assert not failures, f"{len(failures)} of {count} mutants:\n" + "\n".join(failures[:15])
