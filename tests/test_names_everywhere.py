"""Names are free everywhere (issue 37, item 3): a rule base's inputs and output may be called
anything, and a controller spec's ``inputs:`` may name them in any declaration order.

Every command that runs the loop is run on every plant with two user setups:

* ``rulebase``: ``--rulebase force_names.yaml`` (inputs ``force_err``, ``force_rate``, output
  ``dz``: roles by position);
* ``spec``: ``--spec spec_swapped.yaml``, whose rule base declares the inputs the other way
  round (``force_rate`` first) and whose ``inputs: [force_err, force_rate]`` alone says which
  is the error.

The independent reference of each is its twin with fuzzkit's own names: the same rule base
with its variables renamed ``e``, ``de``, ``du`` (declared error first, no ``inputs:``), which
ran before names were free. A name is only a name, so the twin's output must be the renamed
run's, number for number; the rule base's table weighs the error twice its change, so a swap of
the roles would change every run. ``make test`` runs a covering set of command x setup x
plant (:data:`COVER`: each command once), ``make verify`` the full product.
"""

from __future__ import annotations

import csv
import io
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from _codegen_util import needs_cc
from _pairwise import verify

from fuzzkit.cli import main

ROOT = Path(__file__).resolve().parent.parent
USER = ROOT / "tests" / "data" / "user"
PLANTS = ("planar", "arm6", "mujoco", "mujoco-elastic")
SETUPS = ("spec", "rulebase")
#: E1 cut to its contact transient: first contact at about 1.9 s
SHORT_S = 2.6
#: the user's names, and fuzzkit's own that the twin carries instead
RENAMES = {"force_err": "e", "force_rate": "de", "dz": "du"}


class Setup:
    """One setup's files: the renamed one and its twin with fuzzkit's names."""

    def __init__(self, root: Path) -> None:
        scenario = (ROOT / "fuzzkit" / "studies" / "scenarios" / "E1.yaml").read_text("utf-8")
        self.scenario = root / "e1_short.yaml"
        self.scenario.write_text(
            re.sub(r"(?m)^duration_s: .*$", f"duration_s: {SHORT_S}", scenario), "utf-8"
        )
        self.rulebase = USER / "force_names.yaml"
        self.spec = USER / "spec_swapped.yaml"
        text = self.rulebase.read_text("utf-8")
        for old, new in RENAMES.items():
            text = re.sub(rf"\b{old}\b", new, text)
        self.twin_rulebase = root / "plain.yaml"
        self.twin_rulebase.write_text(text, "utf-8")
        spec = self.spec.read_text("utf-8")
        spec = spec.replace("rulebase: force_names_swapped.yaml", f"rulebase: {self.twin_rulebase}")
        self.twin_spec = root / "spec_plain.yaml"
        self.twin_spec.write_text(re.sub(r"(?m)^inputs: .*$", "", spec), "utf-8")

    def source(self, setup: str, twin: bool) -> list[str]:
        """The options that name the controller: a spec, or a rule base."""
        if setup == "spec":
            return ["--spec", str(self.twin_spec if twin else self.spec)]
        return ["--rulebase", str(self.twin_rulebase if twin else self.rulebase)]


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Setup:
    return Setup(tmp_path_factory.mktemp("names"))


#: keys of a run's JSON and table that say where and how fast it ran, or which file it read
VOLATILE = {
    "wall_time_s",
    "cpu_time_s",
    "real_time_factor",
    "controller_impl",
    "simulated_with",  # stability --simulate: the controller_impl of its runs
    "rulebase",
    "controller_spec",
    "gains_source",
    "deployed",  # the certificate's words for the controller (its file's name)
    "table",  # the certificate's table label (its rule base's name)
}


def _stable(value: Any) -> Any:
    """``value`` without the :data:`VOLATILE` keys, at any depth."""
    if isinstance(value, dict):
        return {k: _stable(v) for k, v in value.items() if k not in VOLATILE}
    if isinstance(value, list):
        return [_stable(v) for v in value]
    return value


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    code = main(argv)
    out = capsys.readouterr()
    assert code == 0, out.err
    return out.out


def _corrections(run_csv: str) -> np.ndarray:
    rows = list(csv.DictReader(io.StringIO(run_csv)))
    cols = [c for c in rows[0] if re.fullmatch(r"u[xyz]_m", c)]
    return np.array([[float(r[c]) for c in cols] for r in rows])


def _simulate(extra: list[str]) -> Callable[..., Any]:
    def run(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
        csv_path = out / "run.csv"
        argv = ["simulate", str(f.scenario), *src, "--plant", plant, "--csv", str(csv_path)]
        _cli([*argv, *[x.replace("{out}", str(out)) for x in extra]], capsys)
        text = csv_path.read_text("utf-8")
        assert float(np.max(np.abs(_corrections(text)))) > 1e-5  # the controller corrected
        if "--rrd" in extra:
            assert (out / "run.rrd").stat().st_size > 0
        return text

    return run


def _compare(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    rows = json.loads(_cli(["compare", str(f.scenario), *src, "--plant", plant, "--json"], capsys))
    assert {r["controller"] for r in rows} == {"pi", "fuzzy-pi"}
    return _stable(rows)


def _sweep(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    table = out / "sweep.csv"
    argv = ["sweep", str(f.scenario), *src, "--plant", plant, "--stiffness", "5,10"]
    if src[0] == "--rulebase":
        argv += ["--controller", "fuzzy-pi"]
    _cli([*argv, "--out", str(table), "--workers", "1", "--quiet"], capsys)
    rows = [_stable(r) for r in csv.DictReader(io.StringIO(table.read_text("utf-8")))]
    assert len(rows) == 2
    # a spec run's gains column names the spec file it read (the twin's is another): the rest
    # is the same table
    assert all(r["gains"] == (src[1] if src[0] == "--spec" else "default") for r in rows)
    return [{**r, "gains": "FILE"} for r in rows]


def _tune(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    gains = out / "gains.yaml"
    argv = ["tune", str(f.scenario), *src, "--plant", plant, "--stiffness", "10"]
    if src[0] == "--rulebase":
        argv += ["--controller", "fuzzy-pi"]
    _cli([*argv, "--budget", "10", "--workers", "1", "--quiet", "--out", str(gains)], capsys)
    doc = yaml.safe_load(gains.read_text("utf-8"))
    entry = doc.get("fuzzy-pi", doc)
    gains_found = entry.get("gains", entry)
    return {k: gains_found[k] for k in ("kp", "ki", "kx")}


def _stability(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    argv = ["stability", "regulate", *src, "--plant", plant, "--stiffness", "10"]
    if src[0] == "--rulebase":
        argv += ["--controller", "fuzzy-pi"]
    data = json.loads(
        _cli([*argv, "--latency", "1:1", "--simulate", "--json", "--workers", "1"], capsys)
    )
    assert all("simulated" in c for c in data["cells"])
    return _stable(data)


def _report(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    folder = out / "report"
    gains = ROOT / "docs" / "report" / "gains"
    argv = ["report", "--out", str(folder), "--plant", plant, *src, "--quick"]
    _cli([*argv, "--gains-dir", str(gains), "--no-rrd", "--quiet"], capsys)
    # the report names the file it read (the twin's is another), and the digest of each
    # generated controller (its code spells the names): the rest is the same text
    text = (folder / "report.md").read_text("utf-8").replace(src[1], "FILE")
    return re.sub(r"sha256 [0-9a-f]{16}", "sha256 DIGEST", text)


def _replay(f: Setup, src: list[str], plant: str, out: Path, capsys: Any) -> Any:
    run = out / "run.csv"
    _cli(["simulate", str(f.scenario), *src, "--plant", plant, "--csv", str(run)], capsys)
    spec = src[1]
    replayed = out / "u.csv"
    argv = ["replay", spec, "--forces", str(run), "--out", str(replayed), "--impl", "c"]
    printed = _cli(argv, capsys)
    found = re.search(r"largest difference from the run's corrections \(u<a>_m\): (\S+) m", printed)
    assert found is not None and float(found.group(1)) == 0.0, printed
    return replayed.read_text("utf-8")


COMMANDS: dict[str, Callable[..., Any]] = {
    "simulate": _simulate([]),
    "simulate-loop-python": _simulate(["--loop", "python"]),
    "simulate-impl-python": _simulate(["--controller-impl", "python"]),
    "simulate-impl-reference": _simulate(["--controller-impl", "reference"]),
    "simulate-rrd": _simulate(["--rrd", "{out}/run.rrd"]),
    "compare": _compare,
    "sweep": _sweep,
    "tune": _tune,
    "stability-simulate": _stability,
    "replay": _replay,
    "report": _report,
}
#: what each command cannot take: compare has no --spec, replay needs one
NOT_TAKEN = {("compare", "spec"), ("replay", "rulebase")}


#: ``make test``'s covering set: every command once, every plant and both setups, the costly
#: commands (stability's identification, tune, sweep) on the plants with a compiled loop;
#: the report (about a minute of CPU for the pair) waits for ``make verify``.
COVER = (
    ("simulate", "spec", "mujoco"),
    ("simulate-loop-python", "rulebase", "mujoco-elastic"),
    ("simulate-impl-python", "spec", "arm6"),
    ("simulate-impl-reference", "rulebase", "planar"),
    ("simulate-rrd", "rulebase", "planar"),
    ("compare", "rulebase", "arm6"),
    ("sweep", "spec", "arm6"),
    ("tune", "rulebase", "planar"),
    ("stability-simulate", "spec", "arm6"),
    ("replay", "spec", "mujoco"),
)


def _cases() -> list[Any]:
    """:data:`COVER`, then the full product (``verify``) of command x setup x plant, a setup
    the command cannot take (:data:`NOT_TAKEN`) left out."""
    cover = [pytest.param(*row, id="cover-" + "-".join(row)) for row in COVER]
    full = [
        pytest.param(command, setup, plant, marks=verify, id=f"full-{command}-{setup}-{plant}")
        for command in COMMANDS
        for setup in SETUPS
        for plant in PLANTS
        if (command, setup) not in NOT_TAKEN and (command != "report" or (setup, plant) in REPORTED)
    ]
    return cover + full


#: The report's rows of the full product: each setup once, on the plants with a compiled loop
#: and on MuJoCo (a pair of quick reports costs about 2.4 CPU-minutes on planar, 1.3 on arm6,
#: 6.8 on mujoco; the elastic MuJoCo arm's pair, 6.9, is left out for make verify's budget).
REPORTED = {("rulebase", "planar"), ("spec", "arm6"), ("rulebase", "mujoco")}


@needs_cc
@pytest.mark.parametrize("command, setup, plant", _cases())
def test_a_renamed_controller_runs_as_its_twin_with_fuzzkits_names(
    command: str,
    setup: str,
    plant: str,
    files: Setup,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    run = COMMANDS[command]
    outputs = []
    for twin in (False, True):
        out = tmp_path / ("twin" if twin else "renamed")
        out.mkdir()
        outputs.append(run(files, files.source(setup, twin), plant, out, capsys))
    assert outputs[0] == outputs[1]


@needs_cc
def test_the_user_renamed_spec_runs_on_mujoco(
    files: Setup, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = USER / "spec_renamed.yaml"
    argv = ["simulate", str(files.scenario), "--spec", str(spec), "--plant", "mujoco", "--json"]
    data = json.loads(_cli(argv, capsys))
    assert not data["tripped"] and data["axes"]["z"]["first_contact_s"] is not None
