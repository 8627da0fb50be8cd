"""Names are the user's (issue 29 item 6): keywords of C and Python name rule bases,
variables and terms in every format; generated code mangles them and says so."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import CC, needs_cc

from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.names import symbol
from fuzzkit.codegen.verify import verify_c, verify_exact_c, verify_exact_python, verify_python
from fuzzkit.formats import fcl, fis, fll, registry, yaml_reader
from fuzzkit.fuzzy.inference import evaluate
from fuzzkit.fuzzy.model import RuleBase

#: A rule base made of keywords: C (int, return, while, static, NULL), Python (in, if, None,
#: class, def, lambda, match) and both (if, return, while).
KEYWORDS_YAML = """\
name: class
inputs:
  in:
    range: [-1, 1]
    terms: {partition: triangular, labels: [int, None, return]}
  if:
    range: [-1, 1]
    terms: {partition: triangular, labels: [while, lambda, "NULL"]}  # quoted: YAML null
outputs:
  return:
    range: [-1, 1]
    terms: {partition: triangular, labels: [static, def, match]}
rules:
  table:
    rows: in
    columns: if
    output: return
    cells: |
      static static def
      static def    match
      def    match  match
"""


def _keywords() -> RuleBase:
    return yaml_reader.loads_rulebase(KEYWORDS_YAML, "class.yaml")


def test_symbol_mangles_reserved_words_deterministically_and_nothing_else() -> None:
    # expected spellings written out by hand, not computed by the code under test
    cases = {
        "in": "in_", "int": "int_", "return": "return_", "class": "class_", "None": "None_",
        "NULL": "NULL_", "match": "match_", "__x": "fk__x", "_Foo": "fk_Foo",
        "_Bool": "fk_Bool", "e1": "e1", "macvicar_whelan": "macvicar_whelan", "_x": "_x",
    }  # fmt: skip
    assert {name: symbol(name) for name in cases} == cases


def test_keyword_names_are_read_in_every_format() -> None:
    rb = _keywords()
    assert rb.name == "class" and rb.input_names == ("in", "if")
    # the MATLAB .fis of the issue: a term named 'in' was refused ("a Python keyword")
    for fmt, module in (("fis", fis), ("fcl", fcl), ("fll", fll)):
        back = module.loads(registry.dumps(rb, fmt, allow_loss=True), f"class.{fmt}")
        assert back.input_names == ("in", "if"), fmt
        assert back.inputs[0].term_names == ("int", "None", "return"), fmt
        assert back.outputs[0].name == "return", fmt


@needs_cc
@pytest.mark.parametrize(("method", "number_type"), [("exact", "double"), ("exact", "float"),
                                                     ("table", "double")])  # fmt: skip
def test_generated_c_compiles_and_runs_for_a_rule_base_of_keywords(
    tmp_path: Path, method: str, number_type: str
) -> None:
    rb = _keywords()
    files = dict(compile_rulebase(rb, "c", number_type, method=method, resolution=33).files)
    assert sorted(files) == ["class_.c", "class_.h"]
    assert "rule base 'class' is spelt 'class_'" in " ".join(files["class_.h"].split())
    # compiled by hand with every warning an error, and called by a program of its own
    for rel, text in files.items():
        (tmp_path / rel).write_text(text)
    main = tmp_path / "main.c"
    ctype = "float" if number_type == "float" else "double"
    main.write_text(
        f'#include <stdio.h>\n#include "class_.h"\nint main(void)\n{{\n'
        f"    {ctype} in[2] = {{0.25, -0.5}}, out[1];\n"
        f'    class__eval(in, out);\n    printf("%.9g\\n", (double)out[0]);\n    return 0;\n}}\n'
    )
    exe = tmp_path / "run"
    subprocess.run([*CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", str(main),
                    str(tmp_path / "class_.c"), "-o", str(exe), "-lm"], check=True)  # fmt: skip
    printed = float(subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout)
    engine = float(evaluate(rb, {"in": np.array([0.25]), "if": np.array([-0.5])})["return"][0])
    result = compile_rulebase(rb, "c", number_type, method=method, resolution=33)
    bound = result.table.bound[0] if result.table is not None else 0.0
    assert printed == pytest.approx(engine, abs=bound + 1e-5)
    if result.table is None:
        assert verify_exact_c(rb, number_type, files).ok
    else:
        assert verify_c(rb, result.table, files).ok


@pytest.mark.parametrize("method", ["exact", "table"])
def test_generated_python_imports_and_runs_for_a_rule_base_of_keywords(
    tmp_path: Path, method: str
) -> None:
    rb = _keywords()
    result = compile_rulebase(rb, "python", "double", method=method, resolution=33)
    files = dict(result.files)
    assert sorted(files) == ["class_.py"]
    assert "rule base 'class' is spelt 'class_'" in " ".join(files["class_.py"].split())
    path = tmp_path / "class_.py"
    path.write_text(files["class_.py"])
    spec = importlib.util.spec_from_file_location("class_", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.INPUT_NAMES == ("in", "if")  # the user's names, as strings
    (got,) = module.eval({"in": 0.25, "if": -0.5})
    engine = float(evaluate(rb, {"in": np.array([0.25]), "if": np.array([-0.5])})["return"][0])
    bound = result.table.bound[0] if result.table is not None else 0.0
    assert got == pytest.approx(engine, abs=bound + 1e-9)
    if method == "exact":
        assert verify_exact_python(rb, files).ok
    else:
        assert result.table is not None and verify_python(rb, result.table, files).ok
