"""The user-style rule bases of ``tests/data/user/``: what they are, and that their specs read.

They stand for controllers users bring (issue 28): non-uniform and asymmetric terms, renamed
variables, Gaussian terms with product AND, an imported MATLAB ``.fis``. Other tests drive them
through every command.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzkit.control.spec import surface_inputs
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.fuzzy.inference import evaluate

USER = Path(__file__).resolve().parent / "data" / "user"
#: spec file stem -> (rule base file, its input names, its output name)
USER_SPECS = {
    "nonuniform5": ("nonuniform5.yaml", ("e", "de"), "du"),
    "renamed": ("renamed.yaml", ("err", "derr"), "delta_u"),
    "gauss_prod": ("gauss_prod.yaml", ("e", "de"), "du"),
    "user_pi": ("user_pi.fis", ("error", "rate"), "out"),
}


def user_spec_path(name: str) -> Path:
    """The spec of user-style rule base ``name``."""
    return USER / f"spec_{name}.yaml"


@pytest.mark.parametrize("name", sorted(USER_SPECS))
def test_each_user_spec_reads_with_its_rule_base(name: str) -> None:
    spec = load_spec(user_spec_path(name))
    rb = spec.rulebase
    file, inputs, output = USER_SPECS[name]
    assert rb is not None
    assert spec.rulebase_ref == file
    assert (rb.input_names, rb.output_names) == (inputs, (output,))
    assert surface_inputs(spec, rb) == (0, 1)
    # A PI-like surface: zero at rest, rising with the error and with its change.
    assert evaluate(rb, {inputs[0]: 0.0, inputs[1]: 0.0})[output] == pytest.approx(0.0, abs=1e-12)
    grid = np.linspace(-1.0, 1.0, 41)
    for i, name_in in enumerate(inputs):
        other = inputs[1 - i]
        values = [evaluate(rb, {name_in: float(x), other: 0.0})[output] for x in grid]
        assert np.all(np.diff(values) >= -1e-12), name_in
        assert values[-1] > 0.1 > -0.1 > values[0]


def test_the_non_uniform_one_is_what_the_issue_describes() -> None:
    rb = load_spec(user_spec_path("nonuniform5")).rulebase
    assert rb is not None
    e, de = rb.inputs

    def widths(terms: tuple[object, ...]) -> list[float]:
        return [float(t.params[-1] - t.params[0]) for t in terms]  # type: ignore[attr-defined]

    # inner error terms narrower than the change terms, and the two sides not mirror images
    assert all(a < b for a, b in zip(widths(e.terms)[1:4], widths(de.terms)[1:4], strict=True))
    assert [float(p) for p in e.terms[1].params] != [-float(p) for p in e.terms[3].params[::-1]]


def test_the_gaussian_one_uses_product_and() -> None:
    rb = load_spec(user_spec_path("gauss_prod")).rulebase
    assert rb is not None
    assert rb.operators.and_ == "product"
    assert {t.shape for v in rb.inputs for t in v.terms} == {"gaussian"}
