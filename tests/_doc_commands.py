"""The shell commands of the README and docs/: found, limited where slow, and classified.

A *command block* is a fenced block tagged ``sh``; its lines (backslash continuations joined,
``# comments`` dropped) are commands. Output, usage lines and diagrams go in untagged or
``text`` blocks. ``tests/test_readme.py`` runs every ``fuzzkit`` command of every command block
once, with the earlier commands of its page it depends on (``tests/_doc_plan.py``), in a
scratch folder per group (``tests/_doc_run.py``); a command that cannot run here must be listed in
:data:`NOT_RUN` with the reason, and a slow one is limited by :data:`LIMITS` (smaller budgets,
fewer seeds) but still runs.
"""

from __future__ import annotations

import re
import shlex
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Command:
    page: Path
    line: int
    text: str

    @property
    def where(self) -> str:
        """``page:line``, the page relative to the repository (a page elsewhere: its name)."""
        page = self.page.relative_to(ROOT) if self.page.is_relative_to(ROOT) else self.page.name
        return f"{page}:{self.line}"


def commands(page: Path) -> list[Command]:
    """Every command of the page's ``sh`` blocks, in order, with its line number."""
    out: list[Command] = []
    lines = page.read_text(encoding="utf-8").splitlines()
    in_block = False
    pending: list[str] = []
    start = 0
    for number, raw in enumerate(lines, start=1):
        stripped = raw.strip()
        if stripped.startswith("```"):
            in_block = not in_block and stripped == "```sh"
            continue
        if not in_block:
            continue
        text = _drop_comment(raw).strip()
        if not pending:
            start = number
        if text.endswith("\\"):
            pending.append(text[:-1].strip())
            continue
        pending.append(text)
        joined = " ".join(p for p in pending if p)
        pending = []
        if joined:
            out.append(Command(page, start, joined))
    return out


def _drop_comment(line: str) -> str:
    """The line without its trailing ``# comment`` (a ``#`` outside quotes, after a space)."""
    quote = ""
    for i, ch in enumerate(line):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i]
    return line


#: Commands the test does not run, by how they start, and why.
NOT_RUN: dict[str, str] = {
    "make ": "builds the environment or runs the whole suite (the suite itself runs the tests)",
    "python bench/": "a benchmark: minutes of machine time, its figures are machine-dependent",
    ".venv/bin/dask ": "starts a Dask scheduler or worker: a long-running server",
    "rerun ": "opens the Rerun viewer",
    "fuzzkit ros2 ": "starts a ROS 2 node, a long-running server (tests/test_ros2_node.py runs it)",
    "ros2 ": "the ROS 2 command line (ros2cli) comes with a ROS installation, not with the extra",
    "pip install ": "installs packages (make test's environment holds the extra already)",
}
#: ``fuzzkit`` commands that need a peer the test does not have, by a regex over the command.
NEEDS_PEER: dict[str, str] = {
    r"--scheduler tcp://HOST": "needs a running Dask scheduler at HOST (docs/compiled_loop.md)",
}


def _set_option(argv: list[str], option: str, value: str) -> list[str]:
    """``argv`` with ``option value`` set (replacing a given value)."""
    if option in argv:
        i = argv.index(option)
        return [*argv[: i + 1], value, *argv[i + 2 :]]
    return [*argv, option, value]


def _first_of(argv: list[str], *options: str) -> list[str]:
    """``argv`` with each comma-separated option cut to its first value (one grid cell)."""
    for option in options:
        if option in argv:
            argv = _set_option(argv, option, argv[argv.index(option) + 1].split(",")[0])
    return argv


def _add_flags(argv: list[str], *flags: str) -> list[str]:
    return [*argv, *(f for f in flags if f not in argv)]


#: How slow commands are limited (they still run): by subcommand.
LIMITS: dict[str, Callable[[list[str]], list[str]]] = {
    # one stiffness and one latency: a tune over the 3 x 3 grid on arm6 cost minutes of CPU,
    # and the command's point (its options, --admit, several experiments) holds on one cell;
    # without --stiffness, the first of tune's default 5,10,20 N/mm
    "tune": lambda a: _add_flags(
        _first_of(
            _set_option(_set_option(a, "--budget", "10"), "--workers", "1"),
            "--stiffness",
            "--latency",
        )
        + ([] if "--stiffness" in a else ["--stiffness", "5"]),
        "--quiet",
    ),
    "report": lambda a: _add_flags(
        _set_option(
            _set_option(_set_option(a, "--budget", "10"), "--workers", "1"),
            "--gains-dir",
            str(ROOT / "docs" / "report" / "gains"),
        ),
        "--quick",
        "--no-rrd",
        "--quiet",
    ),
    # one stiffness: 12 runs instead of 36, every other axis of the grid as written
    "sweep": lambda a: _first_of(
        _set_option(_set_option(a, "--seeds", "1"), "--workers", "1"), "--stiffness"
    ),
    "stability": lambda a: _first_of(a, "--stiffness", "--latency"),
}


def not_run_reason(command: str) -> str | None:
    """Why ``command`` is not run here, or None when it is."""
    for start, why in NOT_RUN.items():
        if command.startswith(start):
            return why
    for pattern, why in NEEDS_PEER.items():
        if re.search(pattern, command):
            return why
    return None


def limited(command: str) -> str:
    """``command`` as the test runs it: slow subcommands limited (see :data:`LIMITS`); any
    other command exactly as written (its globs and redirections to the shell)."""
    argv = shlex.split(command, posix=True)
    if len(argv) < 2 or argv[0] != "fuzzkit" or argv[1] not in LIMITS:
        return command
    redirect: list[str] = []
    if ">" in argv:
        i = argv.index(">")
        argv, redirect = argv[:i], argv[i:]
    argv = LIMITS[argv[1]](argv)
    return " ".join(shlex.quote(a) if a != ">" else a for a in [*argv, *redirect])


#: The user's MATLAB file the interop commands name: a water tank's level controller with
#: piecewise-linear terms (every format, both FCL dialects, can hold it).
TANK_FIS = """[System]
Name='tank'
Type='mamdani'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=5
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='level'
Range=[-1 1]
NumMFs=3
MF1='high':'trapmf',[-2 -1 -0.5 0]
MF2='okay':'trimf',[-0.5 0 0.5]
MF3='low':'trapmf',[0 0.5 1 2]

[Input2]
Name='rate'
Range=[-0.1 0.1]
NumMFs=3
MF1='negative':'trimf',[-0.2 -0.1 0]
MF2='none':'trimf',[-0.1 0 0.1]
MF3='positive':'trimf',[0 0.1 0.2]

[Output1]
Name='valve'
Range=[-1 1]
NumMFs=5
MF1='close_fast':'trimf',[-1 -0.9 -0.8]
MF2='close_slow':'trimf',[-0.6 -0.5 -0.4]
MF3='no_change':'trimf',[-0.1 0 0.1]
MF4='open_slow':'trimf',[0.2 0.3 0.4]
MF5='open_fast':'trimf',[0.8 0.9 1]

[Rules]
2 0, 3 (1) : 1
3 0, 5 (1) : 1
1 0, 1 (1) : 1
2 3, 2 (1) : 1
2 1, 4 (1) : 1
"""


def workspace(folder: Path) -> None:
    """Copy what the commands read into ``folder`` (copies: nothing they write reaches the
    repository) and write the user's own files the docs name (``my_rules.yaml`` ...)."""
    shutil.copytree(ROOT / "rulebases", folder / "rulebases")
    shutil.copytree(ROOT / "docs" / "examples", folder / "docs" / "examples")
    shutil.copy(ROOT / "rulebases" / "macvicar_whelan.yaml", folder / "my_rules.yaml")
    shutil.copy(ROOT / "fuzzkit" / "studies" / "scenarios" / "E1.yaml", folder / "my_task.yaml")
    (folder / "tank.fis").write_text(TANK_FIS, encoding="utf-8")
    shutil.copy(ROOT / "docs" / "examples" / "heater.fis", folder / "heater.fis")
    shutil.copy(ROOT / "docs" / "examples" / "controller.yaml", folder / "a.yaml")
    shutil.copy(ROOT / "docs" / "examples" / "controller_pi.yaml", folder / "b.yaml")
    shutil.copy(ROOT / "docs" / "report" / "gains" / "fuzzy-pi.yaml", folder / "gains.yaml")
    (folder / "samples.csv").write_text("e,de\n0.3,-0.2\n-0.5,0.1\n", encoding="utf-8")
    # a press to 12 N, the tool upright (identity rotation: the spec compensates its weight)
    identity = "1,0,0,0,1,0,0,0,1"
    header = "t,fx,fy,fz," + ",".join(f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3))
    rows = [header] + [
        f"{k * 0.004:.3f},0.0,0.0,{min(12.0, 0.05 * k):.3f},{identity}" for k in range(400)
    ]
    (folder / "log.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    write_press_bag(folder / "bag")


def write_press_bag(path: Path) -> None:
    """The press of ``log.csv`` as a ROS 2 bag (sqlite3): a wrench topic ``/ft/wrench`` at
    1 kHz, as a wrist sensor publishes it (``replay`` resamples it to the spec's period)."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.LATEST)
    t = store.types
    msgtype = "geometry_msgs/msg/WrenchStamped"
    with Writer(path, version=9) as writer:
        conn = writer.add_connection("/ft/wrench", msgtype, typestore=store)
        for k in range(1600):
            ns = 1_700_000_000 * 10**9 + k * 1_000_000
            stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            zero = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
            force = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=min(12.0, 0.0125 * k))
            msg = t[msgtype](
                header=t["std_msgs/msg/Header"](stamp=stamp, frame_id="ft_sensor"),
                wrench=t["geometry_msgs/msg/Wrench"](force=force, torque=zero),
            )
            writer.write(conn, ns, store.serialize_cdr(msg, msgtype))
