"""The whole controller generated from a spec (issue 20 item 2): C and Python against the
reference controller, per sample, on random and hostile sensor logs.

The reference is ``fuzzkit.control.reference.Controller`` (the closed loop's controller, the
exact engine as a fuzzy-PI's surface). Every test compiles (gcc and clang, strict flags) or
imports the generated code. Golden files: tests/golden/controller/<spec>/<target>-<type>/;
``FUZZKIT_REFRESH_GOLDEN=1`` rewrites them.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import re
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from _codegen_util import CC, CLANG, needs_cc, require_sanitizers
from _golden import GOLDEN, check_golden, full_scale

from fuzzkit.codegen.backends.c.run import CompiledController
from fuzzkit.codegen.controller import float_step_bound
from fuzzkit.codegen.toolchain import SANITIZE_FLAGS, STRICT_FLAGS, run_compiler
from fuzzkit.control import status as st
from fuzzkit.control.adaptation_spec import Adaptation
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import AxisSpec, ControllerSpec, Limits, SensorSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.controller_code import design_of, generate, open_generated
from fuzzkit.studies.replay import SensorLog, replay
from fuzzkit.studies.sensor_logs import SEGMENTS, hostile_log, hostile_segments

REPO = Path(__file__).parent.parent
EXAMPLES = REPO / "docs" / "examples"
#: Per sample, the double builds equal the reference to this (m), with identical status.
TOLERANCE_M = 1e-9
FloatArray = npt.NDArray[np.float64]


@functools.cache
def spec(variant: str) -> ControllerSpec:
    """The shipped examples and two variants that reach the other branches of the code."""
    if variant == "fuzzy":
        return load_spec(EXAMPLES / "controller.yaml")
    if variant == "pi":
        return load_spec(EXAMPLES / "controller_pi.yaml")
    if variant == "bare_fuzzy":
        # no front end, engaged at once, the default spike gate (half the limit)
        base = spec("fuzzy")
        safety = dataclasses.replace(base.safety, engage_threshold_n=None, spike_gate_n=None)
        return dataclasses.replace(base, name="bare", sensor=SensorSpec(), safety=safety)
    if variant == "hot_pi":
        # all three axes, strong gains and tight limits: |du| and |u| saturate; tare only
        base = spec("pi")
        axes = tuple(AxisSpec(a, sp, 2e-3, 5e-4) for a, sp in (("x", 0.0), ("y", 2.0), ("z", 10.0)))
        return dataclasses.replace(
            base,
            name="hot",
            axes=axes,
            limits=Limits(correction_m=0.003, step_m=2e-4),
            sensor=SensorSpec(tare_samples=10),
        )
    if variant == "adaptive":
        return load_spec(EXAMPLES / "controller_adaptive.yaml")
    if variant == "selftuning":
        return load_spec(EXAMPLES / "controller_selftuning.yaml")
    if variant == "selftuning_fuzzy":
        # self-tuning on the fuzzy-PI's own input scaling, the whole front end, two axes
        base = spec("fuzzy")
        return dataclasses.replace(base, name="stf", adaptation=Adaptation(mode="self-tuning"))
    raise KeyError(variant)


VARIANTS = ("fuzzy", "pi", "bare_fuzzy", "hot_pi", "adaptive", "selftuning", "selftuning_fuzzy")


def reference_run(
    s: ControllerSpec, forces: FloatArray, rotations: FloatArray
) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    """The reference controller (``replay --impl reference``) over a log, from reset."""
    return replay(s, SensorLog(forces, rotations, None), "reference")


@functools.cache
def segments(variant: str) -> dict[str, tuple[FloatArray, FloatArray]]:
    return hostile_segments(spec(variant), n=300, seed=7)


@functools.cache
def reference(variant: str, segment: str) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    return reference_run(spec(variant), *segments(variant)[segment])


def _compiler(name: str) -> list[str]:
    if name == "clang":
        if CLANG is None:
            pytest.skip("clang not installed (apt-get install -y clang); gcc covers it here")
        return [CLANG]
    if CC is None:
        pytest.skip("no C compiler found")
    return CC


def _open(variant: str, impl: str, number_type: str = "double") -> Any:
    s = spec(variant)
    if impl == "python":
        return open_generated(s, "python")
    files = generate(s, "c", number_type)
    return CompiledController(files, f"{s.name}_controller", number_type, compiler=_compiler(impl))


# ------------------------------------------------------------------- equality with the reference


@pytest.mark.parametrize(
    "impl", ["python", pytest.param("cc", marks=needs_cc), pytest.param("clang", marks=needs_cc)]
)
@pytest.mark.parametrize("variant", VARIANTS)
def test_double_controller_equals_the_reference_on_every_hostile_segment(
    variant: str, impl: str
) -> None:
    ctl = _open(variant, impl)
    for name in SEGMENTS:
        forces, rotations = segments(variant)[name]
        ctl.reset()
        got, status = ctl.run(forces, rotations)
        want, want_status = reference(variant, name)
        worst = float(np.max(np.abs(got - want)))
        assert worst <= TOLERANCE_M, (variant, impl, name, worst)
        mismatch = np.flatnonzero(status != want_status)
        assert mismatch.size == 0, (variant, impl, name, mismatch[:5], status[mismatch[:5]])


def test_the_hostile_segments_reach_every_status_bit() -> None:
    # the equality above is only worth what the logs exercise
    seen = 0
    for variant in VARIANTS:
        for name in SEGMENTS:
            seen |= int(np.bitwise_or.reduce(reference(variant, name)[1]))
    # OUT_OF_RANGE needs a contact stiffer than a range's k_max: the safe-start log of
    # tests/test_adaptation.py::test_generated_code_follows_the_safe_start_as_the_reference
    assert seen | st.OUT_OF_RANGE == sum(st.BITS.values()), st.describe(seen)
    tare = reference("fuzzy", "spike_trains")[1]
    gated_tare = st.TARING | st.REJECTED
    assert np.count_nonzero(tare & gated_tare == gated_tare) >= 2  # the tare's spike gate
    tripped = reference("fuzzy", "sustained_over_limit")[1] & st.TRIPPED
    assert tripped.any() and not reference("fuzzy", "random")[1][-1] & st.TRIPPED
    engaged = reference("fuzzy", "random")[1] & st.ENGAGED
    assert not engaged[0] and engaged[-1]


@pytest.mark.parametrize("impl", ["python", pytest.param("cc", marks=needs_cc)])
def test_a_tare_request_mid_log_matches_the_reference(impl: str) -> None:
    s = spec("fuzzy")
    forces, rotations = segments("fuzzy")["tilted_tool"]
    ctl = _open("fuzzy", impl)
    ref = Controller(s)
    for k in range(len(forces)):
        if k == 150:
            ref.tare()
            if impl == "python":
                ctl.controller.tare()
            else:
                ctl.library.e1_fuzzy_controller_request_tare(ctl.state)
        got, status = ctl.step(forces[k].tolist(), rotations[k].tolist())
        want, want_status = ref.step(forces[k].tolist(), rotations[k].tolist())
        assert np.max(np.abs(np.subtract(got, want))) <= TOLERANCE_M and status == want_status, k
    assert want_status & st.ENGAGED


@needs_cc
@pytest.mark.parametrize("variant", ["fuzzy", "hot_pi"])
def test_float_build_stays_within_the_bound_its_header_states(variant: str) -> None:
    s = spec(variant)
    header = generate(s, "c", "float")[f"{s.name}_controller.h"]
    text = " ".join(line.strip(" */") for line in header.splitlines())
    stated = float(re.search(r"grows by at most (\S+) m per period", text).group(1))  # type: ignore[union-attr]
    assert stated == pytest.approx(float_step_bound(design_of(s), 1000.0), rel=1e-2)
    ctl = _open(variant, "cc", "float")
    for name in SEGMENTS:
        forces, rotations = segments(variant)[name]
        # both see the float inputs the float build receives
        f32 = forces.astype(np.float32).astype(np.float64)
        r32 = rotations.astype(np.float32).astype(np.float64)
        ctl.reset()
        got, status = ctl.run(f32, r32)
        want, want_status = reference_run(s, f32, r32)
        err = np.max(np.abs(got - want), axis=1)
        allowed = stated * np.arange(1, len(err) + 1)
        assert np.all(err <= allowed), (name, float(np.max(err / allowed)))
        assert np.array_equal(status, want_status), name


# ------------------------------------------------------------------------ generated-code contracts


@needs_cc
@pytest.mark.parametrize("compiler", ["cc", "clang"])
@pytest.mark.parametrize("variant", ["fuzzy", "hot_pi", "adaptive", "selftuning"])
def test_controller_runs_clean_under_sanitizers(
    tmp_path: Path, compiler: str, variant: str
) -> None:
    s = spec(variant)
    cc = _compiler(compiler)
    module = f"{s.name}_controller"
    for rel, text in generate(s, "c", "double").items():
        (tmp_path / rel).write_text(text)
    (tmp_path / "main.c").write_text(
        f"""#include <stdio.h>
#include "{module}.h"
int main(void)
{{
    {module}_t c;
    double f[3], r[9], u[3];
    int i;
    {module}_init(&c);
    for (;;) {{
        for (i = 0; i < 3; i++) if (scanf("%lf", &f[i]) != 1) return 0;
        for (i = 0; i < 9; i++) if (scanf("%lf", &r[i]) != 1) return 0;
        unsigned long s = (unsigned long){module}_step(&c, f, r, u);
        printf("%.17g %.17g %.17g %lu\\n", u[0], u[1], u[2], s);
    }}
}}
"""
    )
    sources = sorted(p.name for p in tmp_path.glob("*.c"))
    # skip only when the compiler cannot build a trivial sanitized program; the message of a
    # failed real build always names -fsanitize, so matching on it would hide every failure
    require_sanitizers(cc)
    run_compiler([*cc, *STRICT_FLAGS, *SANITIZE_FLAGS, "-o", "h", *sources, "-lm"], tmp_path)
    forces = np.vstack([segments(variant)[n][0] for n in SEGMENTS])
    rotations = np.vstack([segments(variant)[n][1] for n in SEGMENTS])
    lines = (
        " ".join(repr(float(v)) for v in (*f, *r)) for f, r in zip(forces, rotations, strict=True)
    )
    proc = subprocess.run(
        [str(tmp_path / "h")], input="\n".join(lines) + "\n", capture_output=True, text=True,
        timeout=300, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr
    got = np.array([[float(v) for v in line.split()] for line in proc.stdout.splitlines()])
    want, want_status = reference_run(s, forces, rotations)
    assert got.shape == (len(forces), 4)
    assert float(np.max(np.abs(got[:, :3] - want))) <= TOLERANCE_M
    assert np.array_equal(got[:, 3].astype(np.int64), want_status)


@needs_cc
@pytest.mark.parametrize("number_type", ["float", "double"])
@pytest.mark.parametrize("variant", ["fuzzy", "pi", "adaptive", "selftuning_fuzzy"])
def test_objects_use_only_the_libm_symbols_the_header_lists_and_hold_no_writable_data(
    tmp_path: Path, variant: str, number_type: str
) -> None:
    s = spec(variant)
    files = generate(s, "c", number_type)
    for rel, text in files.items():
        (tmp_path / rel).write_text(text)
    cc = _compiler("cc")
    listed: set[str] = set()
    for rel, text in files.items():
        if rel.endswith(".h"):
            uses = re.search(r"Uses from <math.h>: ([^\n(;]*)", text)
            assert uses is not None, rel
            listed |= {w.strip(" .") for w in uses.group(1).split(",")}
    own = {f"{s.name}_surface_eval"}
    for rel in files:
        if not rel.endswith(".c"):
            continue
        run_compiler([*cc, *STRICT_FLAGS, "-O2", "-c", rel, "-o", rel + ".o"], tmp_path)
        nm = subprocess.run(
            ["nm", rel + ".o"], cwd=tmp_path, capture_output=True, text=True, check=True
        )
        undefined = {line.split()[-1] for line in nm.stdout.splitlines() if " U " in line}
        assert undefined <= listed | own, (rel, undefined - listed - own)
        writable = [
            line
            for line in nm.stdout.splitlines()
            if line.split()[-2:-1] in (["D"], ["d"], ["B"], ["b"])
        ]
        assert writable == [], (rel, writable)


def test_python_module_imports_only_the_standard_library() -> None:
    for variant in ("fuzzy", "pi"):
        s = spec(variant)
        text = generate(s, "python")[f"{s.name}_controller.py"]
        tree = ast.parse(text)
        imported = {
            alias.name.split(".")[0]
            for node in ast.walk(tree)
            if isinstance(node, ast.Import)
            for alias in node.names
        } | {
            node.module.split(".")[0]
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.module
        }
        assert imported <= {"__future__", "math", "collections"}, imported


def test_banner_names_the_spec_and_its_sha256_and_no_time() -> None:
    s = spec("fuzzy")
    assert s.source is not None
    for target in ("c", "python"):
        for rel, text in generate(s, target).items():
            if "controller" in rel:
                assert "from controller.yaml" in text and s.source.sha256 in text, rel
            assert not re.search(r"20\d\d-\d\d-\d\d|\d\d:\d\d:\d\d", text), rel
        assert generate(s, target) == generate(s, target)


# ------------------------------------------------------------------------------- golden files

GOLDEN_CASES = [
    ("fuzzy", "c", "double"),
    ("fuzzy", "c", "float"),
    ("fuzzy", "python", "double"),
    ("pi", "c", "float"),
    ("pi", "python", "double"),
]


@pytest.mark.parametrize("variant, target, number_type", GOLDEN_CASES)
def test_controller_matches_golden_files(variant: str, target: str, number_type: str) -> None:
    s = spec(variant)
    files = generate(s, target, number_type)
    folder = GOLDEN / "controller" / s.name / f"{target}-{number_type}"
    # the surface's literals live on the rule base's output range; a PI's are gains and limits,
    # compared relative to themselves (scale 0)
    scale = full_scale(s.rulebase) if s.rulebase is not None else 0.0
    check_golden(folder, files, number_type, scale)


@needs_cc
def test_compiled_code_calls_the_c_controller_by_address() -> None:
    # what a compiled closed loop does: numba calls NAME_controller_step through the ctypes
    # function (typed by its argtypes, address read at call time) on a numpy-held state
    from numba import njit

    s = spec("fuzzy")
    ctl = _open("fuzzy", "cc")
    state = np.zeros(len(ctl.state))
    ctl.init_function(state.ctypes.data)

    @njit(cache=False)
    def run(fn: Any, state: Any, forces: Any, rots: Any, out: Any, status: Any) -> None:
        for k in range(forces.shape[0]):
            status[k] = fn(state.ctypes, forces[k].ctypes, rots[k].ctypes, out[k].ctypes)

    forces, rotations = segments("fuzzy")["tilted_tool"]
    forces = np.ascontiguousarray(forces)
    rotations = np.ascontiguousarray(rotations)
    out = np.zeros((len(forces), 3))
    status = np.zeros(len(forces), dtype=np.int64)
    run(ctl.step_function, state, forces, rotations, out, status)
    want, want_status = reference("fuzzy", "tilted_tool")
    assert float(np.max(np.abs(out - want))) <= TOLERANCE_M
    np.testing.assert_array_equal(status, want_status)
    assert s.name == "e1_fuzzy"


@pytest.mark.parametrize(
    "path", sorted(EXAMPLES.glob("controller*.yaml")), ids=lambda p: Path(p).stem
)
@pytest.mark.parametrize("impl", ["python", pytest.param("cc", marks=needs_cc)])
def test_every_shipped_spec_generates_a_controller_equal_to_its_reference(
    path: Path, impl: str
) -> None:
    s = load_spec(path)
    forces, rotations = hostile_log(s, n=150, seed=11)
    ctl = open_generated(s, "python" if impl == "python" else "c", "double")
    got, status = ctl.run(forces, rotations)
    want, want_status = reference_run(s, forces, rotations)
    assert float(np.max(np.abs(got - want))) <= TOLERANCE_M
    np.testing.assert_array_equal(status, want_status)


def test_codegen_names_mirror_the_controller_names() -> None:
    """codegen may not import fuzzkit.control, so it spells the kinds and axes itself: the
    same names, in the same order, as fuzzkit.control.names (the one definition)."""
    from fuzzkit.codegen import controller as codegen_controller
    from fuzzkit.control import names

    assert codegen_controller.KINDS == names.KINDS
    assert codegen_controller.AXES == names.AXES
