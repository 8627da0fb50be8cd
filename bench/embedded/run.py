"""``make embedded``: the generated code on emulated Cortex-M microcontrollers, bit for bit.

Generates the float controller of ``docs/examples/controller.yaml`` (two force axes,
``macvicar_whelan`` by the exact method, tare + gravity compensation + low-pass) and the
``macvicar_whelan`` Q15 lookup table, cross-compiles them with the test-vector harness
(``harness.c``) for

* Cortex-M4F (hardware single-precision FPU) on QEMU's ``mps2-an386``: the controller's
  surface ``eval`` on random points plus every combination of edge values (0, +-1, +-1e30,
  +-inf, NaN, ...), then the controller ``step`` on a hostile sensor log;
* the same core: the exact float ``eval`` of the 3x3 Gaussian rule base
  (``tests/data/gaussian3x3.yaml``: Gaussian output terms in closed form, ``erfcf``) and of the
  shipped Sugeno controller ``sugeno_pi``, on random points and the edge values;
* Cortex-M3 on ``mps2-an385`` and Cortex-M0 on ``microbit``: the Q15 table's ``eval``;

runs each under QEMU (ARM semihosting for output, ``-icount shift=0``), builds the same harness
for the host, and requires the two outputs to be identical line for line (every output as its
bit pattern; ``-std=c99 -ffp-contract=off`` on both sides). Then it prints flash and RAM bytes
(what linking the code adds to an empty program: code, tables, and every libgcc/libc/libm
routine it pulls in) and instructions per call.

**Instructions, not cycles.** QEMU models no pipeline, caches or wait states: with
``-icount shift=0`` every instruction advances the virtual clock by 1 ns, and SysTick runs off
that clock (25 MHz on mps2: one tick per 40 instructions; 16 MHz on microbit: per 62.5). Each
call (through a function pointer) is timed by reading SysTick before and after; two
back-to-back reads are timed the same way and subtracted, so the figure is the call's own
instructions including the call and return; the mean over all calls is exact to well under
one instruction, the largest single call only to one tick. The host column is nanoseconds per
call (``clock_gettime``) of the same harness built with the host's ``cc -O2``.

Exit status: 0 when every comparison matched, 1 on a mismatch, 2 when a tool is missing.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
SPEC = REPO / "docs" / "examples" / "controller.yaml"
#: Controller specs measured besides SPEC, by row label: the stiffness-scheduled fuzzy-PI
#: (issue 42: its step within 2,500 instructions on the Cortex-M4F).
MORE_SPECS = {"adaptive": REPO / "docs" / "examples" / "controller_adaptive.yaml"}
RULEBASE = "macvicar_whelan"
#: Rule bases whose exact float ``eval`` runs on the Cortex-M4F: (row label, file or name).
EXACT_FLOAT = (
    ("3x3 Gaussian outputs", str(REPO / "tests" / "data" / "gaussian3x3.yaml")),
    ("Sugeno", "sugeno_pi"),
    ("interval type-2 MacVicar-Whelan", "macvicar_whelan_it2"),
)
POINTS = 50_000
#: Edge-value combinations the harness evaluates besides the random points (2 inputs):
#: 17 float edge values, 9 Q15 codes (harness.c).
EDGE_COMBOS = {"float": 17 * 17, "q15": 9 * 9}
PACKAGES = "gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
TOOLS = ("arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-nm", "qemu-system-arm")
#: Both sides: C99, no FMA contraction (the host would otherwise differ where the MCU fuses),
#: and no errno from sqrtf (the code never reads it: the M4F's vsqrt.f32 instead of newlib's
#: errno wrapper and its 1 KB reentrancy block).
COMMON = ("-std=c99", "-ffp-contract=off", "-fno-math-errno", "-O2", "-Wall", "-Wextra")
#: The firmware build the footprint is measured with: unused functions dropped.
GC = ("-ffunction-sections", "-fdata-sections", "-Wl,--gc-sections")
#: Status bits of the generated controller (fuzzkit.control.status)
ENGAGED, HELD, TRIPPED = 1, 2, 4


@dataclass(frozen=True)
class Board:
    """A QEMU machine and how to compile for its core."""

    name: str  # table column
    machine: str
    cpu_flags: tuple[str, ...]
    linker_script: str
    #: instructions per SysTick tick (1 ns per instruction / the SysTick clock)
    insn_per_tick: float


M4F = Board(
    "Cortex-M4F (mps2-an386)",
    "mps2-an386",
    ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"),
    "mps2.ld",
    40.0,
)
M3 = Board("Cortex-M3 (mps2-an385)", "mps2-an385", ("-mcpu=cortex-m3", "-mthumb"), "mps2.ld", 40.0)
M0 = Board("Cortex-M0 (microbit)", "microbit", ("-mcpu=cortex-m0", "-mthumb"), "microbit.ld", 62.5)


@dataclass(frozen=True)
class Row:
    """One line of the table."""

    what: str
    board: str
    flash_bytes: int
    ram_bytes: int
    mean_instructions: float
    max_instructions: float
    tick_instructions: float
    calls: int
    host_instructions: float | None  # x86-64, valgrind callgrind; None: not measured
    host_bytes: int
    identical: bool


def missing_tools() -> list[str]:
    """The cross tools not on PATH."""
    return [t for t in TOOLS if shutil.which(t) is None]


def run(argv: list[str], cwd: Path, timeout: float = 600, stderr: bool = False) -> str:
    """Run a command; its stdout (or stderr). A failure stops the run with its output."""
    proc = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(
            f"{' '.join(argv)} failed ({proc.returncode}):\n{proc.stderr}{proc.stdout}"
        )
    return proc.stderr if stderr else proc.stdout


def float_literal(v: float) -> str:
    """A float32 value as exact C (hex float, or the math.h macros)."""
    x = float(np.float32(v))
    if np.isnan(x):
        return "NAN"
    if np.isinf(x):
        return "INFINITY" if x > 0 else "-INFINITY"
    return f"{x.hex()}f"


def log_source(forces: np.ndarray, rotations: np.ndarray) -> str:
    """``log_data.c``: the sensor log as float32 arrays."""
    n = forces.shape[0]
    rows_f = ",\n".join("    {" + ", ".join(float_literal(v) for v in row) + "}" for row in forces)
    rows_r = ",\n".join(
        "    {" + ", ".join(float_literal(v) for v in row) + "}" for row in rotations
    )
    return (
        "/* generated by bench/embedded/run.py: the hostile sensor log as float32 */\n"
        "#include <math.h>\n\n"
        f"extern const float fk_log_force[{n}][3];\nextern const float fk_log_rot[{n}][9];\n"
        f"const float fk_log_force[{n}][3] = {{\n{rows_f}\n}};\n"
        f"const float fk_log_rot[{n}][9] = {{\n{rows_r}\n}};\n"
    )


def generate(build: Path) -> dict[str, Any]:
    """Write the generated sources and the log into ``build``; what the harness needs."""
    from fuzzkit.codegen.method import compile_rulebase
    from fuzzkit.control.spec_reader import load_spec
    from fuzzkit.formats.registry import load
    from fuzzkit.loop.controller_code import generate as generate_controller
    from fuzzkit.studies.sensor_logs import hostile_log

    controllers = []
    for label, path in {"": SPEC, **MORE_SPECS}.items():
        spec = load_spec(path)
        for rel, text in generate_controller(spec, "c", "float").items():
            (build / rel).write_text(text)
        forces, rotations = hostile_log(spec)
        (build / f"{spec.name}_log_data.c").write_text(log_source(forces, rotations))
        controllers.append({"label": label, "name": spec.name, "log_n": forces.shape[0]})
    rb = load(RULEBASE)
    q15 = compile_rulebase(rb, "c", "q15", method="table")
    for rel, text in q15.files.items():
        (build / rel).write_text(text)
    exact = []
    for _, source in EXACT_FLOAT:
        rb = load(source)
        for rel, text in compile_rulebase(rb, "c", "float", method="exact").files.items():
            (build / rel).write_text(text)
        exact.append(rb.name)
    return {**controllers[0], "controllers": controllers, "exact": exact}


def exact_defines(name: str) -> list[str]:
    """``-D`` flags of the harness for the exact float ``eval`` of rule base ``name``."""
    return [
        f'-DFK_EVAL_HEADER="{name}.h"',
        f"-DFK_EVAL={name}_eval",
        "-DFK_EVAL_T=float",
        "-DFK_NIN=2",
        "-DFK_NOUT=1",
        f"-DFK_POINTS={POINTS}u",
        "-DFK_AMPLITUDE=1.5f",
    ]


def harness_defines(kind: str, info: dict[str, object]) -> list[str]:
    """``-D`` flags of the harness for ``kind``: ``controller`` or ``q15``."""
    if kind == "controller":
        name = info["name"]
        return [
            f'-DFK_EVAL_HEADER="{name}_surface.h"',
            f"-DFK_EVAL={name}_surface_eval",
            "-DFK_EVAL_T=float",
            "-DFK_NIN=2",
            "-DFK_NOUT=1",
            f"-DFK_POINTS={POINTS}u",
            "-DFK_AMPLITUDE=1.5f",
            f'-DFK_CTL_HEADER="{name}_controller.h"',
            f"-DFK_CTL={name}_controller",
            f"-DFK_LOG_N={info['log_n']}",
        ]
    return [
        f'-DFK_EVAL_HEADER="{RULEBASE}.h"',
        f"-DFK_EVAL={RULEBASE}_eval",
        "-DFK_EVAL_T=int16_t",
        "-DFK_NIN=2",
        "-DFK_NOUT=1",
        f"-DFK_POINTS={POINTS}u",
        "-DFK_Q15",
    ]


def sources(kind: str, info: dict[str, object]) -> list[str]:
    """The generated C files of ``kind``."""
    if kind == "controller":
        name = info["name"]
        return [f"{name}_controller.c", f"{name}_surface.c", f"{name}_log_data.c"]
    return [f"{RULEBASE}.c"]


def cross_link(
    build: Path,
    board: Board,
    out: str,
    files: list[str],
    defines: list[str],
    extra: tuple[str, ...] = (),
) -> Path:
    """Compile and link ``files`` with the start-up code for ``board``."""
    argv = [
        "arm-none-eabi-gcc",
        *board.cpu_flags,
        *COMMON,
        *extra,
        f"-I{HERE}",
        f"-I{build}",
        *defines,
        "-nostartfiles",
        "--specs=nosys.specs",
        f"-T{HERE / board.linker_script}",
        "-o",
        out,
        str(HERE / "startup.c"),
        *files,
        "-lm",
    ]
    run(argv, build)
    return build / out


def image_size(build: Path, elf: Path) -> tuple[int, int]:
    """``(flash, ram)`` bytes of an image: text + data, data + bss."""
    line = run(["arm-none-eabi-size", "-B", str(elf)], build).splitlines()[1].split()
    text, data, bss = int(line[0]), int(line[1]), int(line[2])
    return text + data, data + bss


PROBE = """#include "platform.h"
#ifdef FK_CALL
#include FK_CALL_HEADER
#endif
volatile float fk_sink_f[12];
volatile int fk_sink_i[4];
int main(void)
{
    fk_sink_i[3] = 1;    /* both variants keep both sinks: the difference is the code alone */
    fk_sink_f[11] = 0.0f;
#ifdef FK_CALL
    FK_CALL
#endif
    return 0;
}
"""


def footprint(
    build: Path, board: Board, header: str, call: str, files: list[str]
) -> tuple[int, int]:
    """Flash and RAM that calling the code adds to an empty program on ``board``."""
    (build / "probe.c").write_text(PROBE)
    empty = cross_link(build, board, "probe_empty.elf", ["probe.c"], [], GC)
    full = cross_link(
        build,
        board,
        "probe_full.elf",
        ["probe.c", *files],
        [f'-DFK_CALL_HEADER="{header}"', f"-DFK_CALL={call}"],
        GC,
    )
    (f0, r0), (f1, r1) = image_size(build, empty), image_size(build, full)
    return f1 - f0, r1 - r0


def qemu(build: Path, board: Board, elf: Path) -> str:
    """Run ``elf`` on ``board``; its semihosting output."""
    argv = [
        "qemu-system-arm",
        "-M",
        board.machine,
        "-icount",
        "shift=0",
        "-semihosting-config",
        "enable=on,target=native",
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "none",
        "-kernel",
        str(elf),
    ]
    return run(argv, build, timeout=900, stderr=True)  # QEMU writes semihosting to stderr


def host_run(build: Path, out: str, files: list[str], defines: list[str]) -> tuple[str, int]:
    """The harness built for the host and run; its output and the code's object bytes
    (text + data of the generated objects, without the log)."""
    cc = shutil.which("cc") or shutil.which("gcc") or "cc"
    run([cc, *COMMON, f"-I{HERE}", f"-I{build}", *defines, "-o", out,
         str(HERE / "harness.c"), str(HERE / "host.c"), *files, "-lm"], build)  # fmt: skip
    size = 0
    for f in files:
        if f.endswith("log_data.c"):
            continue
        obj = build / (Path(f).stem + ".host.o")
        run([cc, *COMMON, f"-I{build}", "-c", f, "-o", str(obj)], build)
        line = run(["size", "-B", str(obj)], build).splitlines()[1].split()
        size += int(line[0]) + int(line[1])
    return run([str(build / out)], build), size


def host_instructions(build: Path, program: str, function: str, calls: int) -> float | None:
    """x86-64 instructions per call of ``function`` in the host harness (valgrind callgrind,
    inclusive of what it calls); None without valgrind."""
    if shutil.which("valgrind") is None:
        return None
    out = build / f"callgrind.{function}"
    run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
         f"--toggle-collect={function}", str(build / program)], build)  # fmt: skip
    for line in out.read_text().splitlines():
        if line.startswith(("summary:", "totals:")):
            return int(line.split()[1]) / calls
    raise RuntimeError(f"no totals in {out}")


def step_ticks(text: str) -> dict[str, list[float]]:
    """Per controller step: SysTick ticks (calibration subtracted) and whether it ran both
    axes' fuzzy-PI (engaged, neither held nor tripped)."""
    ticks: dict[int, int] = {}
    running: dict[int, bool] = {}
    for line in text.splitlines():
        parts = line.split()
        if parts[0] == "TICK":
            ticks[int(parts[1])] = int(parts[2]) - int(parts[3])
        elif parts[0] == "STEP":
            status = int(parts[2], 16)
            running[int(parts[1])] = bool(status & ENGAGED) and not status & (HELD | TRIPPED)
    return {
        "all": [float(t) for t in ticks.values()],
        "running": [float(t) for k, t in ticks.items() if running[k]],
    }


def timings(text: str) -> dict[str, list[int]]:
    """``TIME what calls total calib max`` lines -> ``{what: [calls, total, calib, max]}``."""
    out = {}
    for line in text.splitlines():
        if line.startswith("TIME "):
            parts = line.split()
            calls = int(parts[2])
            total = (int(parts[3]) << 32) + int(parts[4])
            calib = (int(parts[5]) << 32) + int(parts[6])
            out[parts[1]] = [calls, total, calib, int(parts[7])]
    return out


def compare(target: str, host: str, where: str) -> bool:
    """Every line but TIME identical; prints the first difference."""
    a = [line for line in target.splitlines() if not line.startswith(("TIME ", "TICK "))]
    b = [line for line in host.splitlines() if not line.startswith(("TIME ", "TICK "))]
    if a == b and a and a[-1] == "DONE":
        return True
    for k, (x, y) in enumerate(zip(a, b, strict=False)):
        if x != y:
            print(f"{where}: line {k + 1} differs:\n  target {x}\n  host   {y}")
            break
    else:
        print(f"{where}: {len(a)} target lines, {len(b)} host lines (or no DONE)")
    return False


def measure(build: Path) -> list[Row]:
    """Generate, build, run and compare everything; the table's rows."""
    info = generate(build)
    rows = []
    for ctl in info["controllers"]:
        rows += controller_rows(build, ctl)
    for (label, _), rb_name in zip(EXACT_FLOAT, info["exact"], strict=True):
        rows.append(exact_row(build, label, rb_name))
    rows += q15_rows(build, info)
    return rows


def controller_rows(build: Path, info: dict[str, Any]) -> list[Row]:
    """The controller of ``info`` (and its surface) in float on the Cortex-M4F: its step on
    the engaged periods and on the whole hostile log, and the surface's eval."""
    name = info["name"]
    tag = f"{info['label']} " if info["label"] else ""
    rows = []
    defines = harness_defines("controller", info)
    files = sources("controller", info)
    elf = cross_link(build, M4F, f"{name}_m4f.elf", [str(HERE / "harness.c"), *files], defines)
    target = qemu(build, M4F, elf)
    host, host_bytes = host_run(build, f"{name}_host", files, defines)
    same = compare(target, host, f"controller {name} on " + M4F.name)
    t = timings(target)
    rotation = "{1.0f,0.0f,0.0f,0.0f,-1.0f,0.0f,0.0f,0.0f,-1.0f}"
    ctl_call = (
        f"static {name}_controller_t c; static const float r[9] = {rotation}; float f[3], u[3]; "
        f"{name}_controller_init(&c); f[0] = fk_sink_f[0]; f[1] = fk_sink_f[1]; "
        f"f[2] = fk_sink_f[2]; fk_sink_i[0] = (int){name}_controller_step(&c, f, r, u); "
        "fk_sink_f[3] = u[0]; fk_sink_f[4] = u[1]; fk_sink_f[5] = u[2];"
    )
    flash, ram = footprint(
        build, M4F, f"{name}_controller.h", ctl_call, [f"{name}_controller.c", f"{name}_surface.c"]
    )
    steps = step_ticks(target)
    log_n = int(str(info["log_n"]))
    host_step = host_instructions(build, f"{name}_host", f"{name}_controller_step", log_n)
    host_eval = host_instructions(build, f"{name}_host", f"{name}_surface_eval",
                                  POINTS + EDGE_COMBOS["float"])  # fmt: skip
    running = steps["running"]
    rows.append(Row(
        what=f"{tag}controller step, engaged ({len(running)} of {log_n} steps run both axes)",
        board=M4F.name, flash_bytes=flash, ram_bytes=ram,
        mean_instructions=sum(running) / len(running) * M4F.insn_per_tick,
        max_instructions=max(running) * M4F.insn_per_tick, tick_instructions=M4F.insn_per_tick,
        calls=len(running), host_instructions=None, host_bytes=host_bytes, identical=same,
    ))  # fmt: skip
    rows.append(_row(f"{tag}controller step, whole hostile log", M4F, flash, ram, t["step"],
                     host_step, host_bytes, same))  # fmt: skip
    if info["label"]:
        return rows  # the surface is the same rule base's: measured once
    surf_call = (
        "float in[2], out[1]; in[0] = fk_sink_f[0]; in[1] = fk_sink_f[1]; "
        f"{name}_surface_eval(in, out); fk_sink_f[2] = out[0];"
    )
    flash, ram = footprint(build, M4F, f"{name}_surface.h", surf_call, [f"{name}_surface.c"])
    rows.append(_row("surface eval, exact (float)", M4F, flash, ram, t["eval"], host_eval,
                     0, same))  # fmt: skip
    return rows


def q15_rows(build: Path, info: dict[str, Any]) -> list[Row]:
    """The Q15 table on the Cortex-M3 and M0."""
    rows = []
    defines = harness_defines("q15", info)
    files = sources("q15", info)
    host, host_bytes = host_run(build, "q15_host", files, defines)
    host_q15 = host_instructions(build, "q15_host", f"{RULEBASE}_eval",
                                 POINTS + EDGE_COMBOS["q15"])  # fmt: skip
    q15_call = (
        "int16_t in[2], out[1]; in[0] = (int16_t)fk_sink_i[0]; in[1] = (int16_t)fk_sink_i[1]; "
        f"{RULEBASE}_eval(in, out); fk_sink_i[2] = out[0];"
    )
    for board in (M3, M0):
        tag = board.machine.replace("-", "_")
        elf = cross_link(build, board, f"q15_{tag}.elf", [str(HERE / "harness.c"), *files], defines)
        target = qemu(build, board, elf)
        same = compare(target, host, f"Q15 eval on {board.name}")
        flash, ram = footprint(build, board, f"{RULEBASE}.h", q15_call, files)
        rows.append(_row(f"{RULEBASE} Q15 table eval", board, flash, ram,
                         timings(target)["eval"], host_q15, host_bytes, same))  # fmt: skip
    return rows


def exact_row(build: Path, label: str, name: str) -> Row:
    """The exact float ``eval`` of rule base ``name`` on the Cortex-M4F against the host."""
    defines = exact_defines(name)
    files = [f"{name}.c"]
    elf = cross_link(build, M4F, f"{name}_m4f.elf", [str(HERE / "harness.c"), *files], defines)
    target = qemu(build, M4F, elf)
    host, host_bytes = host_run(build, f"{name}_host", files, defines)
    same = compare(target, host, f"{name} on {M4F.name}")
    call = (
        "float in[2], out[1]; in[0] = fk_sink_f[0]; in[1] = fk_sink_f[1]; "
        f"{name}_eval(in, out); fk_sink_f[2] = out[0];"
    )
    flash, ram = footprint(build, M4F, f"{name}.h", call, files)
    host_eval = host_instructions(build, f"{name}_host", f"{name}_eval",
                                  POINTS + EDGE_COMBOS["float"])  # fmt: skip
    return _row(f"{label} ({name}) eval, exact (float)", M4F, flash, ram,
                timings(target)["eval"], host_eval, host_bytes, same)  # fmt: skip


def _row(what: str, board: Board, flash: int, ram: int, t: list[int], host: float | None,
         host_bytes: int, same: bool) -> Row:  # fmt: skip
    calls, total, calib, max_ticks = t
    mean = (total - calib) * board.insn_per_tick / calls
    return Row(
        what=what,
        board=board.name,
        flash_bytes=flash,
        ram_bytes=ram,
        mean_instructions=mean,
        max_instructions=max_ticks * board.insn_per_tick,
        tick_instructions=board.insn_per_tick,
        calls=calls,
        host_instructions=host,
        host_bytes=host_bytes,
        identical=same,
    )


def table(rows: list[Row]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| code | MCU (QEMU) | flash B | RAM B | instructions/call, mean | largest call | "
        "host x86-64 instructions/call | host object B | bit-identical to host |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        host = "-" if r.host_instructions is None else f"{r.host_instructions:,.0f}"
        lines.append(
            f"| {r.what} | {r.board} | {r.flash_bytes:,} | {r.ram_bytes:,} | "
            f"{r.mean_instructions:,.0f} | {r.max_instructions:,.0f} +-{r.tick_instructions:g} | "
            f"{host} | {r.host_bytes or '-'} | {'yes' if r.identical else 'NO'} "
            f"({r.calls:,} calls) |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=str(REPO / "build" / "embedded"))
    parser.add_argument("--json", help="also write the rows as JSON here")
    args, _ = parser.parse_known_args(argv)
    missing = missing_tools()
    if missing:
        print(f"embedded: {', '.join(missing)} not found; install them (Debian/Ubuntu, as root):\n"
              f"  apt-get install --no-install-recommends {PACKAGES}")  # fmt: skip
        return 2
    build = Path(args.build)
    if build.exists():
        shutil.rmtree(build)
    build.mkdir(parents=True)
    start = time.perf_counter()
    rows = measure(build)
    print(table(rows))
    print(
        "flash/RAM: bytes that calling the code adds to an empty program (code, tables and the "
        "libgcc/libc routines it pulls in; RAM: the controller's state), -O2 -fno-math-errno, "
        "--gc-sections. Instructions: QEMU -icount shift=0 (1 instruction = 1 ns of virtual "
        "time) read through SysTick, the cost of the reads subtracted; QEMU models no "
        "cycles (no pipeline, flash wait states or caches). Host: valgrind callgrind, "
        "instructions of the call including its callees."
    )
    print(f"(embedded: {time.perf_counter() - start:.0f} s)")
    if args.json:
        Path(args.json).write_text(json.dumps([asdict(r) for r in rows], indent=1) + "\n")
    return 0 if all(r.identical for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
