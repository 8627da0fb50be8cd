"""Targets are folders: shared code never branches on a target's name, and a new folder is a
new target (``codegen/README.md``, "Adding a target")."""

from __future__ import annotations

import ast
import dataclasses
import shutil
import sys
import types
from collections.abc import Iterator
from pathlib import Path

import jinja2
import pytest

from fuzzkit.codegen import emit, target
from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.verify import verify_exact_python
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load

CODEGEN = Path(emit.__file__).parent
REPO = Path(__file__).parent.parent
#: Modules every target shares: codegen's own (not its backends), the compile commands and the
#: loop's spec -> generated code path (``--controller-impl c``, ``fuzzkit replay --impl c``
#: choose an implementation there, not a target: studies/replay.py and batch.py are not listed).
SHARED = [
    *sorted(CODEGEN.glob("*.py")),
    REPO / "fuzzkit" / "cli" / "codegen_cmd.py",
    REPO / "fuzzkit" / "cli" / "controller_compile.py",
    REPO / "fuzzkit" / "loop" / "controller_code.py",
    REPO / "fuzzkit" / "loop" / "compiled" / "generated_controller.py",
]


def _target_comparisons(path: Path) -> list[str]:
    """``x == "c"``, ``target != ...``, ``x in ("python", ...)``: a branch on a target."""
    found = []
    names = set(target.TARGETS)
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Compare):
            continue
        parts = [node.left, *node.comparators]
        consts = {
            c.value
            for p in parts
            for c in ast.walk(p)
            if isinstance(c, ast.Constant) and isinstance(c.value, str)
        }
        idents = {
            p.id if isinstance(p, ast.Name) else p.attr
            for p in parts
            if isinstance(p, ast.Name | ast.Attribute)
        }
        if consts & names or "target" in idents:
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_the_scan_finds_a_target_branch() -> None:
    # the check below is only worth something if it sees the branch it forbids
    probe = REPO / "build" / "probe_target_branch.py"
    probe.parent.mkdir(exist_ok=True)
    probe.write_text('py = target == "python"\nok = args.kind in ("c", "other")\n')
    try:
        assert len(_target_comparisons(probe)) == 2
    finally:
        probe.unlink()


def test_no_shared_module_branches_on_a_target() -> None:
    found = [hit for path in SHARED for hit in _target_comparisons(path)]
    assert found == []


def test_targets_are_the_backend_folders() -> None:
    assert target.TARGETS == ("c", "fmu", "python")
    for name in target.TARGETS:
        tg = target.load_target(name)
        assert tg.name == name
        assert tg.folder == CODEGEN / "backends" / name
        assert tg.default_number_type in tg.number_types
        for files in tg.files.values():
            for template in files.values():
                # its own folder first, then the target it extends (the FMU reuses C's)
                assert any((f / template).is_file() for f in tg.template_folders())
    assert target.load_target("fmu").template_folders() == [
        CODEGEN / "backends" / "fmu",
        CODEGEN / "backends" / "c",
    ]


def test_the_jinja_environment_is_strict_and_keeps_layout() -> None:
    env = emit._environment("python")
    assert env.undefined is jinja2.StrictUndefined
    assert env.trim_blocks and env.lstrip_blocks and env.keep_trailing_newline


@pytest.fixture
def toy_target(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[target.Target]:
    """A third target made the way the README says: a folder with templates and a config.

    It is the Python target with every number written as ``float.fromhex(...)`` and its own
    reserved word, registered as the folder scan would register it.
    """
    for template in (CODEGEN / "backends" / "python").glob("*.jinja"):  # includes included
        shutil.copy(template, tmp_path)

    def hex_literal(value: float, number_type: str) -> str:
        return f"float.fromhex({float(value).hex()!r})"

    toy = dataclasses.replace(
        target.load_target("python"),
        name="toy",
        label="Toy",
        folder=tmp_path,
        literal=hex_literal,
        reserved_words=frozenset({"toy_reserved"}),
        files={"exact": {"{name}_toy.py": "exact.py.jinja"}},
    )
    config = types.ModuleType("fuzzkit.codegen.backends.toy.config")
    config.TARGET = toy  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, config.__name__, config)
    monkeypatch.setattr(target, "TARGETS", (*target.TARGETS, "toy"))
    target.load_target.cache_clear()
    yield toy
    target.load_target.cache_clear()


def test_a_new_folder_is_a_new_target(toy_target: target.Target) -> None:
    rb = load("macvicar_whelan")
    files = emit_exact(rb, "toy", "double")
    assert list(files) == ["macvicar_whelan_toy.py"]
    text = files["macvicar_whelan_toy.py"]
    assert "float.fromhex('0x1.0000000000000p+0')" in text
    # the toy module imports and computes what the engine computes
    module_files = {"macvicar_whelan.py": text}
    assert verify_exact_python(rb, module_files, n=2000).ok
    with pytest.raises(CodegenError, match="unknown target 'nope'"):
        emit_exact(rb, "nope", "double")


def test_a_targets_reserved_words_are_refused(toy_target: target.Target) -> None:
    with pytest.raises(CodegenError, match="'toy_reserved' is reserved in Toy"):
        emit.check_identifier("toy_reserved", "name")
    assert emit.check_identifier("toy_allowed", "name") == "toy_allowed"
