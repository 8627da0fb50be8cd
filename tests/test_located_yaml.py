"""The located-YAML API other readers build on (controller specs, gains files, robots)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzkit.errors import ConfigError, ConfigFileError, Location
from fuzzkit.located_yaml import (
    DocumentKind,
    NodeReader,
    load_document,
    locations,
    to_python,
)

KIND = DocumentKind("controller spec", "controller specs", "expected a mapping", ConfigFileError)

SPEC = """\
name: e1
period_s: 4e-3
axes:
  z: {setpoint_n: 10.0, samples: 0x10}
limits: [0.05, .nan]
"""


def test_a_reader_walks_located_nodes_and_raises_every_problem_at_once(tmp_path: Path) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(SPEC)
    root, text = load_document(path, KIND)
    assert text == SPEC
    reader = NodeReader(str(path))
    top = reader.mapping(root, "a spec")
    assert top is not None
    reader.keys(top, root, ("name", "period_s", "axes"), ("name", "safety"), "the spec")
    assert reader.finite(top["period_s"][1], "period_s", 1e-4, 0.1) == 0.004  # YAML 1.2 syntax
    axes = reader.mapping(top["axes"][1], "axes")
    assert axes is not None
    z = reader.mapping(axes["z"][1], "axis z")
    assert z is not None
    assert reader.integer(z["samples"][1], "samples", 1, 100) == 16  # YAML 1.1 hexadecimal
    assert reader.integer(z["setpoint_n"][1], "samples", 1, 100) is None
    limits = reader.sequence(top["limits"][1], "limits")
    assert limits is not None and reader.finite(limits[1], "the step limit") is None
    with pytest.raises(ConfigError) as info:  # ConfigFileError is a ConfigError
        reader.raise_if_any(KIND)
    shown = [str(p) for p in info.value.problems]  # type: ignore[attr-defined]
    assert shown == [
        f"{path}:1:1: missing required key 'safety' in the spec",
        f"{path}:4:19: expected an integer >= 1 for samples (at most 100), got 10.0",
        f"{path}:5:1: unknown key 'limits' in the spec; expected one of name, period_s, axes",
        f"{path}:5:16: the step limit must be a finite number (got nan)",
    ]


def test_plain_data_with_the_places_of_its_keys(tmp_path: Path) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(SPEC)
    root, _ = load_document(path, KIND)
    data = to_python(root, str(path), KIND)
    assert data["period_s"] == 0.004 and data["axes"]["z"]["samples"] == 16
    where = locations(root, str(path))
    assert where[("axes", "z", "samples")] == Location(str(path), 4, 25)
    assert where[("limits", 1)] == Location(str(path), 5, 16)


@pytest.mark.parametrize(
    "text, match",
    [
        ("a: 1\na: 2\n", r"spec.yaml:2:1: duplicate key 'a' \(first defined on line 1\)"),
        ("off: 1\n", r"spec.yaml:1:1: expected a name as key, got off \(YAML reads"),
        ("a: 1\nb: \x1b\n", r"spec.yaml:2:4: control character U\+001B"),
        ("a: " + "9" * 400 + "\n", r"spec.yaml:1:4: integer of 400 digits"),
        ("a: !!python/name:os.system x\n", r"spec.yaml:1:4: unsupported YAML tag"),
        ("# nothing\n", r"spec.yaml:1:1: file is empty"),
    ],
)
def test_plain_data_refuses_what_every_fuzzkit_file_refuses(
    tmp_path: Path, text: str, match: str
) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(text)
    with pytest.raises(ConfigFileError, match=match):
        root, _ = load_document(path, KIND)
        to_python(root, str(path), KIND)
