"""Progress bars (fuzzkit.progress, tqdm): shown on a terminal only, fed by library callbacks."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest

from fuzzkit.codegen.table_search import make_table
from fuzzkit.formats.registry import load
from fuzzkit.progress import TaskBars, progress_bar, progress_wanted
from fuzzkit.studies.tuning import Progress, progress_callback


class FakeTerminal(io.StringIO):
    """A text stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_progress_is_wanted_on_a_terminal_unless_quiet() -> None:
    assert progress_wanted(FakeTerminal())
    assert not progress_wanted(FakeTerminal(), quiet=True)
    assert not progress_wanted(io.StringIO())  # a pipe or a log file
    assert not progress_wanted(None)


def test_a_bar_on_a_terminal_shows_counts_and_an_eta() -> None:
    term = FakeTerminal()
    with progress_bar(10, "work", stream=term, unit="run") as bar:
        for _ in range(4):
            bar.update(1)
    text = term.getvalue()
    assert "work" in text and "4/10" in text
    # tqdm's [elapsed<remaining, rate] block: the ETA
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d", text)


def test_no_output_when_not_a_terminal_or_quiet() -> None:
    for stream, quiet in ((io.StringIO(), False), (FakeTerminal(), True)):
        with progress_bar(3, "work", stream=stream, quiet=quiet) as bar:
            bar.update(3)
        assert stream.getvalue() == ""


def test_tuning_progress_moves_the_bar_to_each_report() -> None:
    term = FakeTerminal()
    with progress_bar(None, "tune", stream=term) as bar:
        show = progress_callback(bar)
        show(Progress("baseline", 1, 40, 5.0, 5.0, 0.1))
        show(Progress("global", 13, 40, 3.25, 5.0, 1.0))
        assert (bar.n, bar.total) == (13, 40)
    text = term.getvalue()
    assert "13/40" in text and "global, best admissible 3.25 (default 5)" in text


def test_task_bars_open_one_bar_per_task() -> None:
    term = FakeTerminal()
    with TaskBars("rb: ", stream=term) as bars:
        bars("5x5 table", 10, 100)
        first = bars.bar
        bars("5x5 table", 100, 100)
        assert bars.bar is first and first.n == 100
        bars("9x9 table", 50, 400)
        assert bars.bar is not first and (bars.bar.n, bars.bar.total) == (50, 400)
    assert bars.bar is None
    assert "rb: 9x9 table" in term.getvalue()


@pytest.mark.parametrize(
    "rulebase, kwargs", [("macvicar_whelan", {}), ("three_input", {"resolution": 7})]
)
def test_table_search_reports_every_evaluated_point_and_the_same_table(
    rulebase: str, kwargs: dict[str, int]
) -> None:
    from fuzzkit.fuzzy.inference import Engine

    rb = load(rulebase)
    engine = Engine(rb)
    counted = {"points": 0}

    def counting(inputs):  # type: ignore[no-untyped-def]
        counted["points"] += int(np.broadcast_arrays(*inputs.values())[0].size)
        return engine.evaluate(inputs)

    calls: list[tuple[str, int, int]] = []
    with_progress = make_table(
        rb,
        evaluate=counting,
        progress=lambda *a: calls.append(a),
        **kwargs,  # type: ignore[arg-type]
    )
    plain = make_table(rb, **kwargs)  # type: ignore[arg-type]
    # Chunked evaluation changes no number of the table or its bound.
    assert with_progress.shape == plain.shape and with_progress.bound == plain.bound
    for a, b in zip(with_progress.stored, plain.stored, strict=True):
        np.testing.assert_array_equal(a, b)
    # Per task, done only grows and never passes total; the last "done" of every task adds
    # up to the points the evaluator really saw.
    last: dict[str, int] = {}
    for task, done, total in calls:
        assert done <= total and done >= last.get(task, 0)
        last[task] = done
    assert sum(last.values()) == counted["points"]
    assert all(re.fullmatch(r"\d+(x\d+)* table", t) for t in last)


def test_python_verify_reports_every_point_twice_and_the_same_outcome() -> None:
    from fuzzkit.codegen.exact import emit_exact
    from fuzzkit.codegen.verify import PROGRESS_CHUNK, verify_exact_python

    rb = load("gaussian5")
    files = emit_exact(rb, "python")
    n = PROGRESS_CHUNK + 100  # two chunks of random points, then edges and weak values
    calls: list[tuple[str, int, int]] = []
    with_progress = verify_exact_python(rb, files, n=n, progress=lambda *a: calls.append(a))
    plain = verify_exact_python(rb, files, n=n)
    # chunked evaluation changes no number: the same errors, exactly
    assert with_progress == plain and plain.ok
    # the generated module's points, then the engine's: done only grows, up to the total
    assert {task for task, _, _ in calls} == {"verify python exact"}
    dones = [done for _, done, _ in calls]
    assert dones == sorted(dones) and calls[-1][1:] == (2 * plain.n_points, 2 * plain.n_points)
    assert len(calls) >= 2 * 3  # each evaluator reports more than once


class _SignalsCtrlCWhenCollected:
    """Sends SIGINT to this process from its finaliser: the KeyboardInterrupt the handler raises
    there is printed and dropped by Python, as one landing in numba's finalisers would be."""

    def __del__(self) -> None:
        import os
        import signal

        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # give the handler bytecode to run on, inside the finaliser
            pass


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_ctrl_c_lost_in_a_finaliser_stops_the_next_progress_update() -> None:
    import gc
    import signal

    from fuzzkit.progress import interrupt_latch, raise_if_interrupted

    before = signal.getsignal(signal.SIGINT)
    with interrupt_latch():
        obj = _SignalsCtrlCWhenCollected()
        del obj  # the KeyboardInterrupt is lost in __del__: nothing is raised here
        gc.collect()
        bar = progress_bar(10, "work", quiet=True)  # silent bars check the latch too
        with pytest.raises(KeyboardInterrupt):
            bar.update(1)
        with pytest.raises(KeyboardInterrupt):
            raise_if_interrupted()
    assert signal.getsignal(signal.SIGINT) is before
    raise_if_interrupted()  # the latch is cleared with the block
    progress_bar(10, "later", quiet=True).update(1)


def test_without_ctrl_c_the_latch_lets_progress_through() -> None:
    from fuzzkit.progress import interrupt_latch, raise_if_interrupted

    with interrupt_latch():
        progress_bar(3, "work", quiet=True).update(3)  # raises nothing
        raise_if_interrupted()


class _FailsWhenCollected:
    def __del__(self) -> None:
        raise ValueError("a finaliser's own error")


def test_the_latch_keeps_a_dropped_ctrl_c_off_stderr_and_passes_other_errors_on(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import gc
    import sys

    from fuzzkit.progress import interrupt_latch, raise_if_interrupted

    seen: list[type[BaseException]] = []
    recorder = lambda info: seen.append(info.exc_type)  # noqa: E731
    monkeypatch.setattr(sys, "unraisablehook", recorder)
    with interrupt_latch():
        obj = _SignalsCtrlCWhenCollected()
        del obj
        gc.collect()
        failing = _FailsWhenCollected()
        del failing
        gc.collect()
        with pytest.raises(KeyboardInterrupt):
            raise_if_interrupted()  # the Ctrl-C was remembered ...
    assert seen == [ValueError]  # ... and only the other finaliser's error was reported
    assert sys.unraisablehook is recorder  # the previous hook comes back with the block
    import signal

    obj = _SignalsCtrlCWhenCollected()  # outside the latch nothing is swallowed
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        del obj
        gc.collect()
    finally:
        signal.signal(signal.SIGINT, previous)
    assert seen == [ValueError, KeyboardInterrupt]


def test_the_shield_holds_the_first_ctrl_c_until_the_work_ends(
    capsys: pytest.CaptureFixture[str],
) -> None:
    import os
    import signal

    from fuzzkit.progress import HELD_NOTE, interrupt_latch, interrupt_shield

    reached_the_end = False
    with interrupt_latch(), pytest.raises(KeyboardInterrupt), interrupt_shield():
        with interrupt_shield():  # nested: held until the outermost ends
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # bytecode for the handler to run on
                pass
        reached_the_end = True
    assert reached_the_end
    assert capsys.readouterr().err.splitlines() == [HELD_NOTE]


def test_a_second_ctrl_c_in_the_shield_is_delivered_at_once() -> None:
    import os
    import signal

    from fuzzkit.progress import interrupt_latch, interrupt_shield

    steps = []
    with interrupt_latch(), pytest.raises(KeyboardInterrupt), interrupt_shield():
        for n in range(2):
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                pass
            steps.append(n)
    assert steps == [0]  # the first was held, the second stopped the work


def test_a_numba_compile_holds_ctrl_c_until_the_kernel_is_compiled() -> None:
    """A Ctrl-C that lands inside numba's compiler (here sent from its first compiler event)
    is delivered after the compile, which completes: LLVM is never cut half-way."""
    import os
    import signal

    import numba
    from numba.core import event

    import fuzzkit.jit  # noqa: F401  (registers the shield with numba's compiler events)
    from fuzzkit.progress import interrupt_latch

    class CtrlCFromTheCompiler(event.Listener):
        sent = False

        def on_start(self, ev: event.Event) -> None:
            if not self.sent:
                self.sent = True
                os.kill(os.getpid(), signal.SIGINT)

        def on_end(self, ev: event.Event) -> None:
            pass

    def add_one(x: int) -> int:
        return x + 1

    kernel = numba.njit(add_one)  # uncached: this call compiles
    probe = CtrlCFromTheCompiler()
    with (
        interrupt_latch(),
        event.install_listener("numba:compiler_lock", probe),
        pytest.raises(KeyboardInterrupt),
    ):
        kernel(1)
    assert probe.sent
    assert len(kernel.signatures) == 1  # the compile ran to its end before the interrupt
    assert kernel(41) == 42
