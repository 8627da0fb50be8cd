"""Two rule bases never compile to the same files or symbols, and ``compile`` never replaces
another source's generated files (issue 40 item 7)."""

from __future__ import annotations

import random
import re
from pathlib import Path

import pytest
from _small_rulebases import SUM_TABLE_3X3

from fuzzkit.cli import main
from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.names import symbol
from fuzzkit.codegen.provenance import source_of
from fuzzkit.formats import yaml_reader
from fuzzkit.fuzzy.validation import C_KEYWORDS, PYTHON_KEYWORDS, identifier_problem

#: the pairs of the issue, and their neighbours, spelt by hand
PAIRS = {
    "in": "in_", "in_": "in__", "in__": "in___", "_X": "fk_X", "fk_X": "fkfk_X",
    "fkfk_X": "fkfkfk_X", "__x": "fk__x", "fk__x": "fkfk__x", "_": "fk_", "fk_": "fkfk_",
    "__": "fk__", "fk": "fk", "fk_x": "fk_x", "x_": "x_", "int_": "int__", "class": "class_",
}  # fmt: skip

#: pieces random names are made of: reserved words, the escapes' prefix and suffix, and
#: ordinary letters, so that collisions of the escapes would be drawn often
PIECES = ("in", "int", "class", "None", "_", "__", "fk", "f", "k", "X", "x", "B", "ool", "1")


def _random_names(n: int, seed: int) -> set[str]:
    rng = random.Random(seed)
    names = set(C_KEYWORDS) | set(PYTHON_KEYWORDS)
    while len(names) < n:
        name = "".join(rng.choice(PIECES) for _ in range(rng.randint(1, 5)))
        if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            names.add(name)
    return names


def test_the_listed_pairs_get_their_own_spellings() -> None:
    assert {name: symbol(name) for name in PAIRS} == PAIRS


def test_the_mapping_is_injective_and_its_spellings_are_usable_identifiers() -> None:
    names = _random_names(30_000, seed=40)
    spelt = {name: symbol(name) for name in names}
    assert len(set(spelt.values())) == len(names)  # no two names share a spelling
    for name, out in spelt.items():
        # every spelling is a C and Python identifier as it is (no keyword, no C-reserved
        # start); the check is the model's own, which the mangling does not call
        assert identifier_problem(out) is None, (name, out)
    # ordinary names (no reserved stem, no leading '_' or 'fk') are kept as they are
    ordinary = [n for n in names if n[0] != "_" and not n.startswith("fk")]
    ordinary = [n for n in ordinary if n.rstrip("_") not in C_KEYWORDS | PYTHON_KEYWORDS]
    assert len(ordinary) > 1000
    assert all(symbol(n) == n for n in ordinary)


RULEBASE = """\
name: {name}
inputs:
  e: {{range: [-1, 1], terms: {{partition: triangular, labels: [N, Z, P]}}}}
  de: {{range: [-1, 1], terms: {{partition: triangular, labels: [N, Z, P]}}}}
outputs:
  du: {{range: [-1, 1], terms: {{partition: triangular, labels: [N, Z, P]}}}}
""" + SUM_TABLE_3X3.replace("{", "{{").replace("}", "}}")


@pytest.mark.parametrize(("first", "second"), [("in", "in_"), ("_X", "fk_X")])
@pytest.mark.parametrize("target", ["c", "python"])
def test_the_issues_pairs_compile_to_different_files(first: str, second: str, target: str) -> None:
    files = [
        set(compile_rulebase(yaml_reader.loads_rulebase(RULEBASE.format(name=n), f"{n}.yaml"),
                             target, "double", method="exact").files)
        for n in (first, second)
    ]  # fmt: skip
    assert files[0] and files[1] and not files[0] & files[1]


def test_every_generated_file_names_its_source_on_its_first_line() -> None:
    rb = yaml_reader.loads_rulebase(RULEBASE.format(name="in"), "in.yaml")
    for target, method in (("c", "exact"), ("c", "table"), ("python", "exact")):
        for text in compile_rulebase(
            rb, target, "double", method=method, resolution=9
        ).files.values():
            assert source_of(text) == "rule base 'in'", (target, method)


def test_compile_refuses_to_overwrite_another_sources_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # spec e1_pi writes e1_pi_controller.{c,h}; a rule base named e1_pi_controller too
    out = tmp_path / "out"
    spec = Path(__file__).parent.parent / "docs" / "examples" / "controller_pi.yaml"
    assert main(["compile", str(spec), "--target", "c", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    rb = tmp_path / "e1_pi_controller.yaml"
    rb.write_text(RULEBASE.format(name="e1_pi_controller"))
    capsys.readouterr()
    code = main(["compile", str(rb), "--target", "c", "--method", "exact", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "controller spec 'e1_pi'" in err and "rule base 'e1_pi_controller'" in err
    assert "Traceback" not in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing written
    # the same source may replace its own files
    assert main(["compile", str(spec), "--target", "c", "--out", str(out)]) == 0


def test_compiling_a_spec_refuses_a_rule_bases_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    rb = tmp_path / "e1_pi_controller.yaml"
    rb.write_text(RULEBASE.format(name="e1_pi_controller"))
    assert (
        main(["compile", str(rb), "--target", "python", "--method", "exact", "--out", str(out)])
        == 0
    )
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    spec = Path(__file__).parent.parent / "docs" / "examples" / "controller_pi.yaml"
    capsys.readouterr()
    assert main(["compile", str(spec), "--target", "python", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "rule base 'e1_pi_controller'" in err and "controller spec 'e1_pi'" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
