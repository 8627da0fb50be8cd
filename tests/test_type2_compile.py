"""``fuzzkit compile`` of interval type-2 rule bases finishes or refuses with the reason.

The exact method has no IT2 emitter yet, so the auto method searches a table; the search for
an IT2 table stops at ``codegen.method.IT2_SEARCH_POINTS`` (the full one took minutes on
``macvicar_whelan_it2``, and mutation fuzzing found a mutant with no answer in 120 s).
"""

from __future__ import annotations

import random
import re
import subprocess
import sys
from pathlib import Path

import pytest
from _mutate import _replace_number

from fuzzkit.codegen import method
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load

SOURCE = Path(method.__file__).resolve().parents[1] / "rulebases" / "macvicar_whelan_it2.yaml"
_NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?![\w.])")


def test_the_it2_table_search_is_capped_and_the_refusal_says_what_to_do(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # auto takes the exact method for an IT2 rule base it covers (tests/test_type2_exact.py);
    # where it cannot (here: said so), the table search over --max-bytes is capped
    monkeypatch.setattr(method, "IT2_SEARCH_POINTS", 64)
    monkeypatch.setattr(method, "unsupported_reason", lambda rb, nt: "not covered")
    rb = load("macvicar_whelan_it2")
    with pytest.raises(CodegenError) as auto:
        method.compile_rulebase(rb, "c", "float", max_bytes=128)
    text = str(auto.value)
    assert "interval type-2 table stops at 64 points" in text and "--resolution N" in text
    assert "within 64 table points" in text
    with pytest.raises(CodegenError, match="within 64 table points"):
        method.compile_rulebase(rb, "c", "float", method="table")


def _one_number_changed(text: str, rng: random.Random) -> tuple[str, str]:
    """Half the time a hostile number (tests/_mutate.py), else one number scaled a little."""
    if rng.random() < 0.5:
        return _replace_number(text, rng)
    found = [m for m in _NUMBER.finditer(text) if not text[: m.start()].rstrip().endswith("#")]
    m = rng.choice(found)
    new = f"{float(m.group()) * rng.uniform(0.5, 1.5) + rng.uniform(-0.1, 0.1):.4f}"
    return text[: m.start()] + new + text[m.end() :], f"{m.group()} -> {new} at {m.start()}"


def _cli(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fuzzkit", *args],
        capture_output=True,
        text=True,
        check=False,
        timeout=timeout,
    )


@pytest.mark.verify
@pytest.mark.parametrize("seed", range(4))
def test_compile_of_a_mutant_it2_rule_base_answers_within_60_s(seed: int, tmp_path: Path) -> None:
    text, what = _one_number_changed(SOURCE.read_text(encoding="utf-8"), random.Random(seed))
    path = tmp_path / "macvicar_whelan_it2.yaml"
    path.write_text(text, encoding="utf-8")
    if _cli("validate", str(path), timeout=60).returncode != 0:
        pytest.skip(f"validate refuses the mutant ({what}): nothing to compile")
    run = _cli("compile", str(path), "--target", "c", "--out", str(tmp_path / "out"), timeout=60)
    assert run.returncode in (0, 2), (what, run.stderr)
    assert "Traceback" not in run.stderr
    if run.returncode == 2:
        assert run.stderr.startswith("fuzzkit: error: "), (what, run.stderr)
        assert not (tmp_path / "out").exists()
