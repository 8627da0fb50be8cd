"""The ``fuzzkit`` command as a process: Ctrl-C (a real SIGINT), closed pipes, ``python -m``."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fuzzkit.progress import HELD_NOTE

FUZZKIT = [sys.executable, "-m", "fuzzkit"]


def _start(
    args: list[str], cwd: Path, extra_env: dict[str, str] | None = None
) -> subprocess.Popen[str]:
    env = {k: v for k, v in os.environ.items() if k != "FUZZKIT_DEBUG"}
    env.update(extra_env or {})
    return subprocess.Popen(
        [*FUZZKIT, *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _wait_for(pred: object, proc: subprocess.Popen[str], timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if callable(pred) and pred():
            return
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"process ended early ({proc.returncode}): {out}{err}")
        time.sleep(0.05)
    proc.kill()
    pytest.fail("timed out waiting for the process to start its work")


def _interrupt(proc: subprocess.Popen[str]) -> tuple[int, str, str]:
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    return proc.returncode, out, err


def _said_on_interrupt(err: str) -> list[str]:
    """stderr's lines after a Ctrl-C, without the note of a Ctrl-C held through a numba compile
    (whether one is in progress when the signal lands depends on the cache and the timing)."""
    lines = err.strip().splitlines()
    return lines[1:] if lines[:1] == [HELD_NOTE] else lines


@pytest.mark.slow
def test_sigint_on_report_exits_130_and_leaves_no_report(tmp_path: Path) -> None:
    out = tmp_path / "report"
    proc = _start(["report", "--out", str(out), "--budget", "10", "--workers", "1"], tmp_path)
    # The staging folder appears once the work has begun (tuning the first controller).
    _wait_for(lambda: any(p.name.endswith(".partial") for p in tmp_path.iterdir()), proc)
    time.sleep(1.0)
    code, stdout, err = _interrupt(proc)
    assert code == 130
    assert _said_on_interrupt(err) == ["fuzzkit: interrupted (Ctrl-C); nothing half-written"]
    assert "Traceback" not in err and "wrote" not in stdout
    assert list(tmp_path.iterdir()) == []  # no report folder, no staging folder


@pytest.mark.slow
def test_sigint_on_report_keeps_an_existing_report_as_it_was(tmp_path: Path) -> None:
    out = tmp_path / "report"
    (out / "rrd").mkdir(parents=True)
    (out / "report.md").write_text("the previous report\n")
    (out / "rrd" / "old.rrd").write_text("x")
    proc = _start(["report", "--out", str(out), "--budget", "10", "--workers", "1"], tmp_path)
    _wait_for(lambda: any(p.name.endswith(".partial") for p in tmp_path.iterdir()), proc)
    time.sleep(1.0)
    code, _, _ = _interrupt(proc)
    assert code == 130
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == [
        "report.md",
        "rrd",
        "rrd/old.rrd",
    ]
    assert (out / "report.md").read_text() == "the previous report\n"


@pytest.mark.slow
def test_sigint_on_compile_exits_130_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "gen"
    # A 3-input table at 41 points per input takes the exact engine well over ten seconds
    # (CC names no compiler, so the table search cannot use the compiled exact sampler).
    proc = _start(
        ["compile", "three_input", "--target", "python", "--method", "table",
         "--resolution", "41", "--out", str(out)],
        tmp_path,
        {"CC": "no-such-compiler"},
    )  # fmt: skip
    time.sleep(4.0)
    assert proc.poll() is None, "compile ended before the interrupt; make the job larger"
    code, _, err = _interrupt(proc)
    assert code == 130
    assert _said_on_interrupt(err) == ["fuzzkit: interrupted (Ctrl-C); nothing half-written"]
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "command",
    [
        "{fk} validate rulebases/*.yaml | head -c 5",
        "{fk} info macvicar_whelan | head -n 1",
        "{fk} schema | head -c 10",
    ],
)
def test_a_closed_pipe_ends_quietly(command: str) -> None:
    root = Path(__file__).resolve().parent.parent
    fk = " ".join(FUZZKIT)
    script = f"set -o pipefail; {command.format(fk=fk)}"
    res = subprocess.run(
        ["bash", "-c", script], cwd=root, capture_output=True, text=True, timeout=120
    )
    assert res.stderr == ""  # no "Broken pipe", no traceback
    assert res.returncode in (0, 141)
    assert res.stdout


def test_demo_into_a_closed_pipe_ends_quietly(tmp_path: Path) -> None:
    fk = " ".join(FUZZKIT)
    res = subprocess.run(
        ["bash", "-c", f"set -o pipefail; {fk} demo --out {tmp_path / 'd'} | head -n 2"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.stderr == ""
    assert res.returncode in (0, 141)
    assert res.stdout.splitlines()[1].startswith("$ fuzzkit validate")
    # It stopped at the first write that failed: no step after validate ran.
    assert not (tmp_path / "d" / "c").exists()


def test_python_dash_m_fuzzkit_is_the_fuzzkit_command() -> None:
    res = subprocess.run(
        [*FUZZKIT, "validate", "macvicar_whelan"], capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("macvicar_whelan: ok (rule base macvicar_whelan: 2 inputs")
    bad = subprocess.run([*FUZZKIT, "validate", "no_such_rb"], capture_output=True, text=True)
    assert bad.returncode == 2 and "no_such_rb" in bad.stderr and "Traceback" not in bad.stderr


@pytest.mark.slow
def test_sigint_on_tune_exits_130_and_keeps_the_best_so_far(tmp_path: Path) -> None:
    from fuzzkit.control.gains import read_gains_file

    out = tmp_path / "gains.yaml"
    args = ["tune", "E1", "--controller", "pi", "--stiffness", "10", "--budget", "400"]
    # the Python loop: the compiled one would finish 400 evaluations before the interrupt
    proc = _start([*args, "--loop", "python", "--workers", "2", "--out", str(out)], tmp_path)
    time.sleep(8.0)  # start-up plus the baseline evaluation, then well into the search
    assert proc.poll() is None, "tune ended before the interrupt; raise the budget"
    code, stdout, err = _interrupt(proc)
    assert code == 130
    assert _said_on_interrupt(err) == [
        f"fuzzkit: interrupted (Ctrl-C); {out} holds the best gains so far"
    ]
    assert "(interrupted: best so far)" in stdout
    entry = read_gains_file(out)["pi"]
    assert entry.provenance["interrupted"] is True and entry.provenance["evaluations"] < 400
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gains.yaml"]  # no temporary left


def test_a_ctrl_c_that_left_c_api_code_still_exits_130(tmp_path: Path) -> None:
    """Under ``python -m``, CPython 3.11 kills itself with SIGINT at shutdown, whatever exit
    code was asked for, once a KeyboardInterrupt has left code run through ``PyRun_String``
    (as seen with a Ctrl-C landing while scipy imports, inside a Cython module's init). The
    command must still end with 130 and its one line."""
    (tmp_path / "interrupted_in_c_api.py").write_text(
        "import ctypes\n"
        "import sys\n"
        "import fuzzkit.cli.rulebase as rb\n"
        "run = ctypes.pythonapi.PyRun_String\n"
        "run.restype = ctypes.py_object\n"
        "run.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.py_object, ctypes.py_object]\n"
        "def interrupted(args):\n"
        "    run(b'raise KeyboardInterrupt', 257, {}, {})  # 257: Py_file_input\n"
        "rb.cmd_validate = interrupted\n"
        "from fuzzkit.cli import console_main\n"
        "sys.argv = ['fuzzkit', 'validate', 'macvicar_whelan']\n"
        "console_main()\n"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), *sys.path]))
    res = subprocess.run(
        [sys.executable, "-m", "interrupted_in_c_api"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,
    )
    assert res.returncode == 130, res.stderr
    assert res.stderr.splitlines() == ["fuzzkit: interrupted (Ctrl-C); nothing half-written"]
