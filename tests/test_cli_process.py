"""The ``fuzzkit`` command as a process: Ctrl-C (a real SIGINT), closed pipes, ``python -m``."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

import pytest

from fuzzkit.progress import HELD_NOTE

FUZZKIT = [sys.executable, "-m", "fuzzkit"]


def _start(
    args: list[str],
    cwd: Path,
    extra_env: dict[str, str] | None = None,
    stderr: int = subprocess.PIPE,
) -> subprocess.Popen[str]:
    env = {k: v for k, v in os.environ.items() if k != "FUZZKIT_DEBUG"}
    env["PYTHONFAULTHANDLER"] = "1"  # a crash prints its Python stack on stderr
    env.update(extra_env or {})
    return subprocess.Popen(
        [*FUZZKIT, *args], cwd=cwd, stdout=subprocess.PIPE, stderr=stderr, text=True, env=env
    )


def _wait_for(pred: object, proc: subprocess.Popen[str], timeout_s: float = 120.0) -> None:
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


class Terminal:
    """A pseudo-terminal for a command's stderr, so that it draws its progress bars (only a
    terminal gets them); a thread collects what the command writes there."""

    def __init__(self) -> None:
        self.fd, self.child_fd = pty.openpty()
        # 24 rows of 200 columns: a terminal of no width gets bars of no text
        fcntl.ioctl(self.child_fd, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 200, 0, 0))
        self._text = bytearray()
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)

    def start(self) -> None:
        os.close(self.child_fd)  # the command holds its own copy
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                chunk = os.read(self.fd, 65536)
            except OSError:  # EIO: every writer has closed the terminal
                break
            if not chunk:
                break
            with self._lock:
                self._text += chunk

    def text(self) -> str:
        with self._lock:
            return self._text.decode("utf-8", errors="replace")

    def shows(self, pattern: str) -> bool:
        return re.search(pattern, self.text()) is not None

    def lines(self) -> list[str]:
        """The lines as they stand on the screen: each one's text after its last carriage
        return (a redrawn bar), without terminal escapes, blank lines dropped."""
        self._reader.join(timeout=30)
        os.close(self.fd)
        plain = re.sub(r"\x1b\[[0-9;]*[A-Za-z]", "", self.text())
        shown = [ln.rsplit("\r", 1)[-1].rstrip() for ln in plain.split("\r\n")]
        return [ln for ln in shown if ln]


def _start_on_terminal(
    args: list[str], cwd: Path, extra_env: dict[str, str] | None = None
) -> tuple[subprocess.Popen[str], Terminal]:
    """``fuzzkit ARGS`` with stderr on a :class:`Terminal` (stdout piped)."""
    terminal = Terminal()
    proc = _start(args, cwd, extra_env, stderr=terminal.child_fd)
    terminal.start()
    return proc, terminal


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
    args = ["report", "--out", str(out), "--budget", "10", "--workers", "1"]
    proc, terminal = _start_on_terminal(args, tmp_path)
    # The staging folder exists and the first controller's tuning has evaluated a gain set.
    _wait_for(lambda: terminal.shows(r"tuning pi: .*\b[1-9]/10"), proc, 300.0)
    assert any(p.name.endswith(".partial") for p in tmp_path.iterdir())
    code, stdout, _ = _interrupt(proc)
    assert code == 130
    said = [ln for ln in terminal.lines() if not ln.startswith("tuning pi: ")]
    assert _said_on_interrupt("\n".join(said)) == [
        "fuzzkit: interrupted (Ctrl-C); nothing half-written"
    ]
    assert "wrote" not in stdout
    assert list(tmp_path.iterdir()) == []  # no report folder, no staging folder


@pytest.mark.slow
def test_sigint_on_report_keeps_an_existing_report_as_it_was(tmp_path: Path) -> None:
    out = tmp_path / "report"
    (out / "rrd").mkdir(parents=True)
    (out / "report.md").write_text("the previous report\n")
    (out / "rrd" / "old.rrd").write_text("x")
    args = ["report", "--out", str(out), "--budget", "10", "--workers", "1"]
    proc, terminal = _start_on_terminal(args, tmp_path)
    _wait_for(lambda: terminal.shows(r"tuning pi: .*\b[1-9]/10"), proc, 300.0)
    code, _, _ = _interrupt(proc)
    said = terminal.lines()  # the terminal closed
    assert code == 130, "\n".join(said[-40:])
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
    proc, terminal = _start_on_terminal(
        ["compile", "three_input", "--target", "python", "--method", "table",
         "--resolution", "41", "--out", str(out)],
        tmp_path,
        {"CC": "no-such-compiler"},
    )  # fmt: skip
    # the table search's progress bar, with some exact-engine points evaluated
    _wait_for(lambda: terminal.shows(r"three_input: .*\b[1-9][\d.]*k?/"), proc, 300.0)
    assert proc.poll() is None, "compile ended before the interrupt; make the job larger"
    code, _, _ = _interrupt(proc)
    assert code == 130
    said = [ln for ln in terminal.lines() if not ln.startswith("three_input: ")]
    assert _said_on_interrupt("\n".join(said)) == [
        "fuzzkit: interrupted (Ctrl-C); nothing half-written"
    ]
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_sigint_on_python_verify_shows_its_bar_exits_130_and_writes_nothing(
    tmp_path: Path,
) -> None:
    out = tmp_path / "gen"
    gaussian = Path(__file__).parent / "data" / "gaussian3x3.yaml"
    # 1e5 points through the pure-Python module: about 15 s, drawn as a bar on a terminal
    proc, terminal = _start_on_terminal(
        ["compile", str(gaussian), "--target", "python", "--method", "exact", "--verify",
         "--out", str(out)],
        tmp_path,
    )  # fmt: skip
    _wait_for(lambda: terminal.shows(r"verify python exact: .*\b[1-9][\d.]*k?/200k"), proc, 120.0)
    assert proc.poll() is None, "verify ended before the interrupt; make the job larger"
    code, stdout, _ = _interrupt(proc)
    assert code == 130
    said = [ln for ln in terminal.lines() if "verify python exact: " not in ln]
    assert _said_on_interrupt("\n".join(said)) == [
        "fuzzkit: interrupted (Ctrl-C); nothing half-written"
    ]
    assert "wrote" not in stdout
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
    # head may exit before or after the command has written everything: 0 or 141
    root = Path(__file__).resolve().parent.parent
    fk = " ".join(FUZZKIT)
    script = f"set -o pipefail; {command.format(fk=fk)}"
    res = subprocess.run(
        ["bash", "-c", script], cwd=root, capture_output=True, text=True, timeout=120
    )
    assert res.stderr == ""  # no "Broken pipe", no traceback
    assert res.returncode in (0, 141)
    assert res.stdout


def test_a_pipe_closed_before_the_first_write_is_141() -> None:
    # docs/cli.md's example: `true` exits before fuzzkit has started, so its first write fails
    root = Path(__file__).resolve().parent.parent
    script = f"set -o pipefail; {' '.join(FUZZKIT)} validate rulebases/*.yaml | true"
    res = subprocess.run(
        ["bash", "-c", script], cwd=root, capture_output=True, text=True, timeout=120
    )
    assert (res.returncode, res.stderr) == (141, "")


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
    proc, terminal = _start_on_terminal(
        [*args, "--loop", "python", "--workers", "2", "--out", str(out)], tmp_path
    )
    # the progress bar past the baseline evaluation: the search has gains to keep
    _wait_for(lambda: terminal.shows(r"tune pi: .*\b([2-9]|\d\d+)/400"), proc, 300.0)
    assert proc.poll() is None, "tune ended before the interrupt; raise the budget"
    code, stdout, _ = _interrupt(proc)
    assert code == 130
    said = [ln for ln in terminal.lines() if not ln.startswith("tune pi: ")]
    lines = _said_on_interrupt("\n".join(said))
    # the honest-tuning warnings about the best so far may come first; the interrupt note last
    assert lines[-1:] == [f"fuzzkit: interrupted (Ctrl-C); {out} holds the best gains so far"]
    assert all(ln.startswith("warning: ") for ln in lines[:-1]), lines
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
