"""Generated exact code carries the variables' units in its header, as the table code does."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine

ROOT = Path(__file__).resolve().parent.parent
UNITS_LINE = "Units: e [K], de [K/s], power [%]"


def _with_units(tmp_path: Path) -> Path:
    text = (ROOT / "rulebases" / "temperature_pd.yaml").read_text(encoding="utf-8")
    text = text.replace(
        "  e:\n    range: [-20, 20]\n", "  e:\n    range: [-20, 20]\n    units: K\n"
    )
    text = text.replace(
        "  de:\n    range: [-2, 2]\n", "  de:\n    range: [-2, 2]\n    units: K/s\n"
    )
    text = text.replace(
        "  power:\n    range: [0, 100]\n", '  power:\n    range: [0, 100]\n    units: "%"\n'
    )
    path = tmp_path / "heater.yaml"
    path.write_text(text, encoding="utf-8")
    assert [v.units for v in (*load(str(path)).inputs, *load(str(path)).outputs)] == [
        "K", "K/s", "%",
    ]  # fmt: skip
    return path


def _compile(capsys: pytest.CaptureFixture[str], *args: str) -> None:
    assert main(["compile", *args, "--quiet"]) == 0, capsys.readouterr().err
    capsys.readouterr()


def test_exact_c_and_python_headers_state_the_units_as_the_table_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    src = str(_with_units(tmp_path))
    exact_c, exact_py, table_c = tmp_path / "exact_c", tmp_path / "exact_py", tmp_path / "table_c"
    _compile(capsys, src, "--target", "c", "--method", "exact", "--out", str(exact_c), "--verify")
    _compile(capsys, src, "--target", "python", "--method", "exact", "--out", str(exact_py))
    _compile(capsys, src, "--target", "c", "--method", "table", "--tolerance", "0.05",
             "--out", str(table_c))  # fmt: skip
    table_header = (table_c / "temperature_pd.h").read_text()
    assert f" * {UNITS_LINE}\n" in table_header  # the table's header, the reference
    header = (exact_c / "temperature_pd.h").read_text()
    source = (exact_c / "temperature_pd.c").read_text()
    assert f" * {UNITS_LINE}\n" in header and f" * {UNITS_LINE}\n" in source
    listed = {
        line.split("]", 1)[0].strip(" *") + "]": line.rsplit(" ", 1)[-1]
        for line in header.splitlines()
        if line.startswith((" *   in[", " *   out["))
    }
    assert listed == {"in[0]": "[K]", "in[1]": "[K/s]", "out[0]": "[%]"}
    module = (exact_py / "temperature_pd.py").read_text()
    assert f"\n{UNITS_LINE}\n" in module.split('"""')[1]  # in the module docstring
    # the generated module still runs and agrees with the engine
    monkeypatch.syspath_prepend(str(exact_py))
    sys.modules.pop("temperature_pd", None)
    mod = importlib.import_module("temperature_pd")
    want = Engine(load(src)).evaluate_point({"e": 3.0, "de": -0.5})["power"]
    assert mod.eval({"e": 3.0, "de": -0.5})[0] == pytest.approx(want, abs=1e-9)
    sys.modules.pop("temperature_pd", None)


def test_no_units_no_units_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "c"
    _compile(capsys, "temperature_pd", "--target", "c", "--method", "exact", "--out", str(out))
    assert "Units:" not in (out / "temperature_pd.h").read_text()
