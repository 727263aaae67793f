"""The generated C on a Cortex-M4F: cross-build, sizes, stack, and an emulated TDROC run.

``python -m runtime.firmware_report [--out docs/FIRMWARE.md]`` (needs ``arm-none-eabi-gcc``
with newlib; the emulated run also needs ``unicorn``):

1. compiles every ``generated/c/wmr_*.c`` with :data:`ARM_FLAGS` (``-Werror``), float32
   (``-DWMR_FLOAT32``) and double, with ``-fstack-usage -fcallgraph-info=su``;
2. links, per controller, a tiny ``main`` (init + one step, float32) with newlib-nano
   (``--specs=nano.specs --specs=nosys.specs``, ``--gc-sections``) and lists the
   double-precision helper symbols in the ELF (``__aeabi_d*``, ``__aeabi_f2d``, ...:
   there must be none);
3. reports ``.text``/``.data``/``.bss`` per ELF (``arm-none-eabi-size``), and per
   generated function its code size (``nm -S``), its own frame (``.su``) and the
   worst-case stack through its callees: the call graph of ``-fcallgraph-info`` for
   generated code, and for library callees (``sinf``, ``memcpy``, ...) their frames
   and ``bl`` targets read from the linked ELF's disassembly (push/vpush/sub sp);
4. runs the float32 TDROC step (paper formulation) in the Unicorn emulator (Cortex-M4,
   FPU) on a recorded closed-loop sequence (the lawn-mower path through
   ``runtime.simulate.run(float32=True)``, ε = 0.5), and compares its torques with the
   host float32 build (in ulps) and the host double build; counts the instructions
   executed per step and measures the stack's high-water mark.

Everything is written to ``docs/FIRMWARE.md``.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import struct
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from runtime.cbuild import GENERATED_C

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "FIRMWARE.md"
ARM_GCC = "arm-none-eabi-gcc"
ARM_FLAGS = (
    "-mcpu=cortex-m4",
    "-mthumb",
    "-mfloat-abi=hard",
    "-mfpu=fpv4-sp-d16",
    "-Os",
    "-Werror",
    "-std=c99",
    "-Wall",
    "-Wextra",
)
# Per-function sections so that the links below keep only what is called.
SECTION_FLAGS = ("-ffunction-sections", "-fdata-sections")
CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")
# Soft-float double helpers of libgcc (EABI names and their GNU aliases).
DOUBLE_SYMBOL = re.compile(
    r"^(__aeabi_d\w*|__aeabi_[filu]+2d|__aeabi_ul2d|__\w+df[23]|__extendsfdf2|__truncdfsf2)$"
)
EMU_BASE = 0x20000000
EMU_SIZE = 1 << 20
EMU_STACK = 0x4000  # bytes of stack below EMU_BASE + EMU_SIZE
STACK_FILL = 0xCD


def tool(name: str) -> str | None:
    """Path of ``arm-none-eabi-<name>`` (None if the toolchain is not installed)."""
    return shutil.which(f"arm-none-eabi-{name}")


def have_toolchain() -> bool:
    return all(tool(t) for t in ("gcc", "nm", "size", "objdump", "objcopy"))


def have_newlib() -> bool:
    """True if the toolchain can link a program (newlib installed)."""
    if not have_toolchain():
        return False
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "t.c"
        src.write_text("int main(void) { return 0; }\n")
        cmd = [ARM_GCC, *ARM_FLAGS, "--specs=nano.specs", "--specs=nosys.specs", str(src)]
        return (
            subprocess.run([*cmd, "-o", str(Path(tmp) / "t.elf")], capture_output=True).returncode
            == 0
        )


def supports_callgraph_info() -> bool:
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "t.c"
        src.write_text("int f(void) { return 0; }\n")
        cmd = [ARM_GCC, *ARM_FLAGS, "-fcallgraph-info=su", "-c", str(src), "-o", f"{tmp}/t.o"]
        return subprocess.run(cmd, capture_output=True, cwd=tmp).returncode == 0


def _run(cmd: Sequence[str], cwd: Path | None = None) -> str:
    proc = subprocess.run(list(cmd), capture_output=True, text=True, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stdout}{proc.stderr}")
    return proc.stdout


def generated_sources() -> list[Path]:
    """Every generated .c except example_main.c."""
    return sorted(GENERATED_C.glob("wmr_*.c"))


def toolchain_version() -> str:
    return _run([ARM_GCC, "--version"]).splitlines()[0]


# ------------------------------------------------------------------------- compiling
@dataclass(frozen=True)
class Objects:
    """Objects of one precision with their stack-usage (.su) and call-graph (.ci) files."""

    dir: Path
    float32: bool
    objects: tuple[Path, ...]
    su: tuple[Path, ...]
    ci: tuple[Path, ...]
    warnings: str  # compiler output (empty: no diagnostics at all)


def compile_generated(out: Path, float32: bool, callgraph: bool | None = None) -> Objects:
    """Compile each generated .c with ARM_FLAGS (+ -DWMR_FLOAT32) into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    callgraph = supports_callgraph_info() if callgraph is None else callgraph
    flags = [*ARM_FLAGS, *SECTION_FLAGS, "-fstack-usage", f"-I{GENERATED_C}"]
    if callgraph:
        flags.append("-fcallgraph-info=su")
    if float32:
        flags.append("-DWMR_FLOAT32")
    objs, su, ci, diagnostics = [], [], [], []
    for src in generated_sources():
        obj = out / f"{src.stem}.o"
        proc = subprocess.run(
            [ARM_GCC, *flags, "-c", str(src), "-o", str(obj)],
            capture_output=True,
            text=True,
            cwd=out,
        )
        if proc.returncode != 0:
            raise RuntimeError(f"{src.name} does not compile for the Cortex-M4:\n{proc.stderr}")
        diagnostics.append(proc.stdout + proc.stderr)
        objs.append(obj)
        su.append(out / f"{src.stem}.su")
        if callgraph:
            ci.append(out / f"{src.stem}.ci")
    return Objects(out, float32, tuple(objs), tuple(su), tuple(ci), "".join(diagnostics))


MAIN_TEMPLATE = """\
#include "wmr_{name}.h"
#include "wmr_robot.h"

/* A minimal firmware image: one controller, initialised and stepped once. */
static wmr_{name}_state_t state;
volatile wmr_real_t sink;
volatile wmr_real_t sensor = WMR_LIT(0.1);

int main(void)
{{
    wmr_{name}_config_t config = {{0}};
    const wmr_params_t nominal = WMR_ROBOT_PARAMS_INIT;
    wmr_real_t q[5], qdot[5], q_des[5], qdot_des[5], qddot_des[5], tau[2];
    wmr_status_t status;
    int i;
    config.nominal = nominal;
    config.formulation = WMR_FORMULATION_PAPER;
    for (i = 0; i < 5; ++i) {{
        config.k1[i] = WMR_LIT(4.0);
        config.k2[i] = WMR_LIT(4.0);
        q[i] = sensor;
        qdot[i] = sensor;
        q_des[i] = sensor;
        qdot_des[i] = sensor;
        qddot_des[i] = sensor;
    }}
    config.q_pos = WMR_LIT(1.0);
    config.q_vel = WMR_LIT(1.0);
    config.h = WMR_LIT(0.1);
    config.tau_max = WMR_LIT(40.0);
{extra}
    if (wmr_{name}_init(&state, &config) != WMR_OK) {{
        return 1;
    }}
    status = wmr_{name}_step(&state, &config, q, qdot, q_des, qdot_des, qddot_des, tau);
    sink = tau[0] + tau[1];
    return status < 0;
}}
"""
MAIN_EXTRA = {
    "tdc": "    config.accel_estimator = WMR_ACCEL_BACKWARD;",
    "tdroc": "    config.accel_estimator = WMR_ACCEL_BACKWARD;\n    config.eps = WMR_LIT(0.5);\n"
    "    config.n = 4;\n    config.a = WMR_LIT(0.9);",
    "roc": "    config.eps = WMR_LIT(0.1);\n    config.alpha = WMR_LIT(0.3);\n"
    "    config.phi = WMR_LIT(4.0);",
    "asmc": "    config.eps = WMR_LIT(0.1);\n    config.gamma = WMR_LIT(2.0);\n"
    "    config.gain0 = WMR_LIT(0.0);",
}


def link_controller(objs: Objects, name: str) -> Path:
    """ELF of a tiny main calling wmr_<name>_init and _step, linked with newlib-nano."""
    main = objs.dir / f"main_{name}.c"
    main.write_text(MAIN_TEMPLATE.format(name=name, extra=MAIN_EXTRA[name]))
    elf = objs.dir / f"{name}.elf"
    flags = [*ARM_FLAGS, *SECTION_FLAGS, "-fstack-usage", f"-I{GENERATED_C}"]
    if objs.float32:
        flags.append("-DWMR_FLOAT32")
    _run(
        [
            ARM_GCC,
            *flags,
            str(main),
            *map(str, objs.objects),
            "--specs=nano.specs",
            "--specs=nosys.specs",
            "-Wl,--gc-sections",
            "-lm",
            "-o",
            str(elf),
        ],
        cwd=objs.dir,
    )
    return elf


def symbols(elf: Path) -> dict[str, tuple[int, int, str]]:
    """name -> (address, size, type) of every symbol with a size."""
    out = {}
    for line in _run([str(tool("nm")), "-S", str(elf)]).splitlines():
        parts = line.split()
        if len(parts) == 4:
            out[parts[3]] = (int(parts[0], 16), int(parts[1], 16), parts[2])
    return out


def all_symbol_names(elf: Path) -> list[str]:
    return [line.split()[-1] for line in _run([str(tool("nm")), str(elf)]).splitlines() if line]


def double_symbols(elf: Path) -> list[str]:
    """Soft-float double helpers linked into the ELF (must be empty for the float build)."""
    return sorted(s for s in all_symbol_names(elf) if DOUBLE_SYMBOL.match(s))


def elf_sizes(elf: Path) -> dict[str, int]:
    """text, data, bss of ``arm-none-eabi-size`` (Berkeley format)."""
    line = _run([str(tool("size")), str(elf)]).splitlines()[1].split()
    return {"text": int(line[0]), "data": int(line[1]), "bss": int(line[2])}


# ---------------------------------------------------------------------------- stack
@dataclass
class Frame:
    """One function's own stack frame and whom it calls."""

    name: str
    own: int
    qualifier: str  # static | dynamic | bounded (from .su), "elf" (from the disassembly)
    callees: set[str] = field(default_factory=set)
    size: int = 0  # code bytes


_CI_NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
_CI_EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
_CI_SIZE = re.compile(r"\\n(\d+) bytes \((\w+)\)")


def parse_callgraph(ci_files: Sequence[Path]) -> dict[str, Frame]:
    """Frames of the compiled functions from ``-fcallgraph-info=su`` files, keyed by the
    plain function name (a static clone such as ``f.constprop.0`` keeps its own key)."""
    titles: dict[str, str] = {}  # .ci title -> plain name
    frames: dict[str, Frame] = {}
    edges: list[tuple[str, str]] = []
    for path in ci_files:
        text = path.read_text()
        for title, label in _CI_NODE.findall(text):
            plain = title.rsplit(":", 1)[-1] if ":" in title else title
            titles[title] = plain
            m = _CI_SIZE.search(label)
            if m:
                frames[plain] = Frame(plain, int(m.group(1)), m.group(2))
        edges += _CI_EDGE.findall(text)
    for src, dst in edges:
        caller = titles.get(src, src)
        callee = titles.get(dst, dst)
        if caller in frames and callee != caller:
            frames[caller].callees.add(callee)
    return frames


def parse_su(su_files: Sequence[Path]) -> dict[str, tuple[int, str]]:
    """name -> (bytes, qualifier) from ``-fstack-usage`` files."""
    out = {}
    for path in su_files:
        for line in path.read_text().splitlines():
            where, size, qual = line.split("\t")
            out[where.rsplit(":", 1)[-1]] = (int(size), qual)
    return out


_FN_HEADER = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
_REGS = re.compile(r"\{([^}]*)\}")
_SUB_SP = re.compile(r"\bsub(?:\.w|w)?\s+sp,\s*(?:sp,\s*)?#(\d+)")
_CALL = re.compile(r"\b(?:bl|blx|b\.w|b)\s+[0-9a-f]+ <([^>+]+)>")


def _count_regs(text: str) -> int:
    n = 0
    for part in text.split(","):
        part = part.strip()
        if "-" in part:
            lo, hi = (int(re.sub(r"\D", "", x)) for x in part.split("-"))
            n += hi - lo + 1
        elif part:
            n += 1
    return n


def elf_frames(elf: Path) -> dict[str, Frame]:
    """Frames read from the disassembly: push/stmdb sp! (4 bytes a register), vpush of
    d (8) or s (4) registers, sub sp; callees: bl/blx and branches into other functions
    (tail calls, counted as calls: conservative)."""
    frames: dict[str, Frame] = {}
    current: Frame | None = None
    text = _run([str(tool("objdump")), "-d", "--no-show-raw-insn", str(elf)])
    for line in text.splitlines():
        header = _FN_HEADER.match(line)
        if header:
            current = Frame(header.group(2), 0, "elf")
            frames[current.name] = current
            continue
        if current is None or ":\t" not in line:
            continue
        insn = line.split(":\t", 1)[1]
        mnemonic = insn.split()[0] if insn.split() else ""
        if mnemonic in ("push", "push.w") or insn.startswith("stmdb\tsp!"):
            m = _REGS.search(insn)
            current.own += 4 * _count_regs(m.group(1)) if m else 0
        elif mnemonic == "vpush" or insn.startswith("vstmdb\tsp!"):
            m = _REGS.search(insn)
            if m:
                width = 8 if m.group(1).strip().startswith("d") else 4
                current.own += width * _count_regs(m.group(1))
        else:
            m = _SUB_SP.search(insn)
            if m:
                current.own += int(m.group(1))
        call = _CALL.search(insn)
        if call and call.group(1) != current.name:
            current.callees.add(call.group(1))
    return frames


@dataclass(frozen=True)
class StackBound:
    bytes: int
    path: tuple[str, ...]  # the deepest call chain
    complete: bool  # False: a callee's frame is unknown, or recursion


def worst_stack(
    name: str, frames: dict[str, Frame], library: dict[str, Frame] | None = None
) -> StackBound:
    """Own frame + the deepest callee chain. Generated functions come from ``frames``
    (.su/.ci); anything else from ``library`` (the linked ELF's disassembly)."""
    library = library or {}
    memo: dict[str, StackBound] = {}

    def visit(fn: str, active: tuple[str, ...]) -> StackBound:
        if fn in active:
            return StackBound(0, (fn, "<recursion>"), False)
        if fn in memo:
            return memo[fn]
        frame = frames.get(fn) or library.get(fn)
        if frame is None:
            builtin = fn.removeprefix("__builtin_")
            frame = library.get(builtin)
        if frame is None:
            return StackBound(0, (fn + "?",), False)
        best = StackBound(0, (), True)
        complete = frame.qualifier in ("static", "elf")
        for callee in sorted(frame.callees):
            sub = visit(callee, (*active, fn))
            complete = complete and sub.complete
            if sub.bytes > best.bytes or not best.path:
                best = sub
        result = StackBound(frame.own + best.bytes, (fn, *best.path), complete)
        memo[fn] = result
        return result

    return visit(name, ())


# ------------------------------------------------------------------------ emulation
IO_FIELDS: tuple[tuple[str, int, str], ...] = (
    ("params", 7, "f"),
    ("k1", 5, "f"),
    ("k2", 5, "f"),
    ("q_pos", 1, "f"),
    ("q_vel", 1, "f"),
    ("h", 1, "f"),
    ("tau_max", 1, "f"),
    ("eps", 1, "f"),
    ("a", 1, "f"),
    ("formulation", 1, "i"),
    ("accel_estimator", 1, "i"),
    ("n", 1, "i"),
    ("status", 1, "i"),
    ("in", 25, "f"),
    ("tau", 2, "f"),
    ("gain", 1, "f"),
    ("s_norm", 1, "f"),
)
PARAM_FIELDS = ("m", "Iz", "K", "Iw", "r", "b", "d")


def io_offsets() -> dict[str, tuple[int, int, str]]:
    """field -> (byte offset, count, struct code) of the harness's ``wmr_io``."""
    out, offset = {}, 0
    for name, count, code in IO_FIELDS:
        out[name] = (offset, count, code)
        offset += 4 * count
    return out


def harness_source() -> str:
    decl = "\n".join(
        f"    {'float' if c == 'f' else 'int'} {n}{f'[{k}]' if k > 1 else ''};"
        for n, k, c in IO_FIELDS
    )
    params = "\n".join(
        f"    cfg.nominal.{p} = wmr_io.params[{i}];" for i, p in enumerate(PARAM_FIELDS)
    )
    return f"""\
#include "wmr_tdroc.h"

/* Emulator harness: the host writes wmr_io, calls harness_init/harness_step and reads
   wmr_io back; harness_done is the return address (an endless loop). */
typedef struct {{
{decl}
}} wmr_io_t;
wmr_io_t wmr_io;
static wmr_tdroc_config_t cfg;
static wmr_tdroc_state_t state;

void harness_done(void)
{{
    for (;;) {{
    }}
}}

void harness_init(void)
{{
    int i;
{params}
    for (i = 0; i < 5; ++i) {{
        cfg.k1[i] = wmr_io.k1[i];
        cfg.k2[i] = wmr_io.k2[i];
    }}
    cfg.q_pos = wmr_io.q_pos;
    cfg.q_vel = wmr_io.q_vel;
    cfg.h = wmr_io.h;
    cfg.tau_max = wmr_io.tau_max;
    cfg.eps = wmr_io.eps;
    cfg.a = wmr_io.a;
    cfg.formulation = wmr_io.formulation;
    cfg.accel_estimator = wmr_io.accel_estimator;
    cfg.n = wmr_io.n;
    wmr_io.status = wmr_tdroc_init(&state, &cfg);
}}

void harness_step(void)
{{
    wmr_io.status = wmr_tdroc_step(&state, &cfg, wmr_io.in, wmr_io.in + 5, wmr_io.in + 10,
                                   wmr_io.in + 15, wmr_io.in + 20, wmr_io.tau);
    wmr_io.gain = state.gain;
    wmr_io.s_norm = state.s_norm;
}}
"""


LINKER_SCRIPT = f"""\
MEMORY {{ RAM (rwx) : ORIGIN = {EMU_BASE:#x}, LENGTH = {EMU_SIZE - EMU_STACK:#x} }}
SECTIONS {{
  .text : {{ *(.text*) *(.rodata*) }} > RAM
  .data : {{ *(.data*) }} > RAM
  .bss (NOLOAD) : {{ *(.bss*) *(COMMON) }} > RAM
  /DISCARD/ : {{ *(.ARM.exidx*) *(.ARM.extab*) }}
}}
"""


def link_emulator_image(objs: Objects) -> tuple[Path, Path]:
    """(ELF, flat binary at EMU_BASE) of the TDROC harness, float32, newlib-nano libm."""
    assert objs.float32
    harness = objs.dir / "harness.c"
    harness.write_text(harness_source())
    script = objs.dir / "emu.ld"
    script.write_text(LINKER_SCRIPT)
    elf, binary = objs.dir / "emu.elf", objs.dir / "emu.bin"
    _run(
        [
            ARM_GCC,
            *ARM_FLAGS,
            *SECTION_FLAGS,
            "-DWMR_FLOAT32",
            f"-I{GENERATED_C}",
            str(harness),
            *map(str, objs.objects),
            "--specs=nano.specs",
            "-nostartfiles",
            "-T",
            str(script),
            "-Wl,--gc-sections",
            "-Wl,-e,harness_step",
            "-Wl,-u,harness_init",
            "-Wl,-u,harness_done",
            "-lm",
            "-o",
            str(elf),
        ],
        cwd=objs.dir,
    )
    _run([str(tool("objcopy")), "-O", "binary", str(elf), str(binary)])
    return elf, binary


class Emulator:
    """The harness in Unicorn (Cortex-M4 with FPU): call functions, count instructions,
    measure the stack's high-water mark."""

    def __init__(self, elf: Path, binary: Path) -> None:
        from unicorn import UC_ARCH_ARM, UC_HOOK_BLOCK, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
        from unicorn.arm_const import UC_CPU_ARM_CORTEX_M4

        self.syms = {k: v[0] for k, v in symbols(elf).items()}
        self.syms.update(self._all_addresses(elf))
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M4)
        self.uc.mem_map(EMU_BASE, EMU_SIZE)
        self.uc.mem_write(EMU_BASE, binary.read_bytes())
        self.io = self.syms["wmr_io"]
        self.offsets = io_offsets()
        self.instructions = 0
        self._block_counts: dict[tuple[int, int], int] = {}
        self.uc.hook_add(UC_HOOK_BLOCK, self._on_block)

    @staticmethod
    def _all_addresses(elf: Path) -> dict[str, int]:
        out = {}
        for line in _run([str(tool("nm")), str(elf)]).splitlines():
            parts = line.split()
            if len(parts) == 3:
                out[parts[2]] = int(parts[0], 16)
        return out

    def _on_block(self, uc: Any, address: int, size: int, user: Any) -> None:
        key = (address, size)
        count = self._block_counts.get(key)
        if count is None:  # Thumb-2: a halfword 0b11101/0b11110/0b11111... starts a 32-bit insn
            code = bytes(uc.mem_read(address, size))
            count, i = 0, 0
            while i < size:
                half = code[i] | (code[i + 1] << 8)
                i += 4 if (half >> 11) in (0b11101, 0b11110, 0b11111) else 2
                count += 1
            self._block_counts[key] = count
        self.instructions += count

    def write(self, name: str, values: Sequence[float]) -> None:
        offset, count, code = self.offsets[name]
        assert len(values) == count, name
        self.uc.mem_write(self.io + offset, struct.pack(f"<{count}{code}", *values))

    def read(self, name: str) -> tuple[Any, ...]:
        offset, count, code = self.offsets[name]
        return struct.unpack(
            f"<{count}{code}", bytes(self.uc.mem_read(self.io + offset, 4 * count))
        )

    def call(self, function: str) -> tuple[int, int]:
        """Run ``function()``; (instructions executed, stack bytes used)."""
        from unicorn.arm_const import UC_ARM_REG_LR, UC_ARM_REG_SP

        top = EMU_BASE + EMU_SIZE
        bottom = top - EMU_STACK
        self.uc.mem_write(bottom, bytes([STACK_FILL]) * EMU_STACK)
        self.uc.reg_write(UC_ARM_REG_SP, top)
        self.uc.reg_write(UC_ARM_REG_LR, self.syms["harness_done"] | 1)
        before = self.instructions
        self.uc.emu_start(self.syms[function] | 1, self.syms["harness_done"])
        stack = bytes(self.uc.mem_read(bottom, EMU_STACK))
        untouched = len(stack) - len(stack.lstrip(bytes([STACK_FILL])))
        return self.instructions - before, EMU_STACK - untouched


@dataclass(frozen=True)
class Recording:
    """A closed-loop run's controller inputs and outputs, step by step."""

    config: dict[str, Any]
    inputs: list[list[list[float]]]  # per step: q, qdot, q_des, qdot_des, qddot_des
    status: list[int]
    tau: list[list[float]]
    gain: list[float]


def record_closed_loop(
    controller: str = "tdroc", formulation: str = "paper", eps: float = 0.5, float32: bool = True
) -> Recording:
    """Run ``simulate.run`` on the lawn-mower path and record every controller call."""
    from modeling.robot_file import load_robot
    from runtime import references, simulate
    from runtime.cbuild import CLibrary
    from runtime.experiment import Experiment

    robot = dict(load_robot().lumped)
    exp = Experiment()
    exp = replace(exp, controller=replace(exp.controller, eps=eps))
    ref = references.lawnmower(robot, exp.controller.h, exp.paths.lawnmower_duration)
    real = simulate.sim_library(float32)
    rec: dict[str, list[Any]] = {"inputs": [], "status": [], "tau": [], "gain": [], "cfg": []}
    step_name = f"wmr_{controller}_step"

    class Recorder:
        def __getattr__(self, attr: str) -> Any:
            fn = getattr(real.lib, attr)
            if attr != step_name:
                return fn

            def step(state: Any, cfg: Any, *args: Any) -> int:
                status = int(fn(state, cfg, *args))
                if not rec["cfg"]:
                    rec["cfg"].append(config_values(real.ffi, cfg))
                rec["inputs"].append([[float(x) for x in a] for a in args[:5]])
                rec["status"].append(status)
                rec["tau"].append([float(args[5][0]), float(args[5][1])])
                rec["gain"].append(float(state.gain))
                return status

            return step

    original = simulate.sim_library

    def recording_library(float32: bool = False) -> CLibrary:
        return CLibrary(real.ffi, Recorder(), real.float32, real.path)

    simulate.sim_library = recording_library  # type: ignore[assignment]
    try:
        simulate.run(controller, formulation, ref, robot, exp, float32=float32)
    finally:
        simulate.sim_library = original
    return Recording(rec["cfg"][0], rec["inputs"], rec["status"], rec["tau"], rec["gain"])


def config_values(ffi: Any, cfg: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"params": [float(getattr(cfg.nominal, p)) for p in PARAM_FIELDS]}
    for name, _ in ffi.typeof(cfg[0]).fields:
        if name == "nominal":
            continue
        value = getattr(cfg, name)
        out[name] = [float(x) for x in value] if isinstance(value, ffi.CData) else value
    return out


def replay_host(rec: Recording, float32: bool) -> tuple[list[int], list[list[float]], list[float]]:
    """The recorded inputs through the host build (cffi), TDROC: (status, tau, gain)."""
    from runtime import cbuild

    lib = cbuild.build(float32)
    ffi = lib.ffi
    cfg = ffi.new("wmr_tdroc_config_t *")
    for i, p in enumerate(PARAM_FIELDS):
        setattr(cfg.nominal, p, rec.config["params"][i])
    for name, value in rec.config.items():
        if name != "params":
            setattr(cfg, name, value)
    state = ffi.new("wmr_tdroc_state_t *")
    if lib.lib.wmr_tdroc_init(state, cfg) != 0:
        raise RuntimeError("host init failed")
    tau = ffi.new("wmr_real_t[2]")
    statuses, taus, gains = [], [], []
    for inputs in rec.inputs:
        arrays = [ffi.new("wmr_real_t[5]", v) for v in inputs]
        statuses.append(int(lib.lib.wmr_tdroc_step(state, cfg, *arrays, tau)))
        taus.append([float(tau[0]), float(tau[1])])
        gains.append(float(state.gain))
    return statuses, taus, gains


@dataclass(frozen=True)
class EmulationResult:
    steps: int
    instructions: list[int]
    stack_bytes: int  # high-water mark over all steps (measured)
    init_instructions: int
    status: list[int]
    tau: list[list[float]]
    gain: list[float]


def emulate(rec: Recording, elf: Path, binary: Path) -> EmulationResult:
    emu = Emulator(elf, binary)
    cfg = rec.config
    emu.write("params", cfg["params"])
    for name in ("k1", "k2"):
        emu.write(name, cfg[name])
    for name in (
        "q_pos",
        "q_vel",
        "h",
        "tau_max",
        "eps",
        "a",
        "formulation",
        "accel_estimator",
        "n",
    ):
        emu.write(name, [cfg[name]])
    init_insns, _ = emu.call("harness_init")
    if emu.read("status")[0] != 0:
        raise RuntimeError(f"emulated init failed: {emu.read('status')[0]}")
    counts, stack, status, taus, gains = [], 0, [], [], []
    for inputs in rec.inputs:
        emu.write("in", [x for v in inputs for x in v])
        n, used = emu.call("harness_step")
        counts.append(n)
        stack = max(stack, used)
        status.append(int(emu.read("status")[0]))
        taus.append(list(emu.read("tau")))
        gains.append(float(emu.read("gain")[0]))
    return EmulationResult(len(counts), counts, stack, init_insns, status, taus, gains)


def ulps(a: float, b: float) -> int:
    """Distance between two float32 values in units in the last place."""

    def ordered(x: float) -> int:
        i: int = struct.unpack("<i", struct.pack("<f", x))[0]
        return i if i >= 0 else -(i & 0x7FFFFFFF)

    if math.isnan(a) or math.isnan(b):
        return 2**31
    return abs(ordered(a) - ordered(b))


@dataclass(frozen=True)
class Comparison:
    max_ulps: int  # ARM vs host float32, torques
    median_ulps: float
    max_abs_vs_float: float
    scale_ulps_vs_float: float  # max abs difference in ulps of the run's largest |torque|
    torque_scale: float  # the run's largest |torque| (host double) [N m]
    max_abs_vs_double: float  # ARM vs host double, torques [N m]
    max_rel_vs_double: float  # relative to max |tau| of the run
    host_float_reproduces_loop: bool
    same_status: bool


def compare(rec: Recording, emu: EmulationResult) -> Comparison:
    s_f, tau_f, _ = replay_host(rec, True)
    s_d, tau_d, _ = replay_host(rec, False)
    arm = np.array(emu.tau)
    tf, td = np.array(tau_f), np.array(tau_d)
    dist = [ulps(a, b) for a, b in zip(arm.ravel(), tf.ravel(), strict=True)]
    scale = float(np.max(np.abs(td)))
    return Comparison(
        max_ulps=max(dist),
        median_ulps=float(np.median(dist)),
        max_abs_vs_float=float(np.max(np.abs(arm - tf))),
        scale_ulps_vs_float=float(np.max(np.abs(arm - tf)) / np.spacing(np.float32(scale))),
        torque_scale=scale,
        max_abs_vs_double=float(np.max(np.abs(arm - td))),
        max_rel_vs_double=float(np.max(np.abs(arm - td)) / scale),
        host_float_reproduces_loop=tau_f == rec.tau and s_f == rec.status,
        same_status=emu.status == s_f == s_d,
    )


# --------------------------------------------------------------------------- report
@dataclass
class Report:
    version: str
    float_objs: Objects
    double_objs: Objects
    elves: dict[str, Path]
    sizes: dict[str, dict[str, int]]
    doubles: dict[str, list[str]]
    frames: dict[str, Frame]
    library: dict[str, Frame]
    functions: list[tuple[str, int, int, str, StackBound]]  # name, size, own, qual, bound
    step_stack: dict[str, StackBound]
    own_text: dict[str, int]
    emulation: EmulationResult | None = None
    comparison: Comparison | None = None
    notes: list[str] = field(default_factory=list)


def build_report(work: Path, emulate_run: bool = True) -> Report:
    """Compile, link, analyse (and emulate) in ``work``."""
    f32 = compile_generated(work / "float32", True)
    f64 = compile_generated(work / "double", False)
    elves = {name: link_controller(f32, name) for name in CONTROLLERS}
    sizes = {name: elf_sizes(elf) for name, elf in elves.items()}
    doubles = {name: double_symbols(elf) for name, elf in elves.items()}
    frames = parse_callgraph(f32.ci)
    su = parse_su(f32.su)
    for name, (own, qual) in su.items():  # .su is authoritative for the frame
        if name in frames:
            frames[name].own, frames[name].qualifier = own, qual
        else:
            frames[name] = Frame(name, own, qual)
    library: dict[str, Frame] = {}
    for elf in elves.values():
        for name, frame in elf_frames(elf).items():
            library.setdefault(name, frame)
    code_sizes: dict[str, int] = {}
    for obj in f32.objects:
        for name, (_, size, kind) in symbols(obj).items():
            if kind in "tT":
                code_sizes[name] = size
    functions = []
    for name in sorted(code_sizes):
        if not name.startswith("wmr_") or name not in frames:
            continue
        fr = frames[name]
        functions.append(
            (name, code_sizes[name], fr.own, fr.qualifier, worst_stack(name, frames, library))
        )
    step_stack = {c: worst_stack(f"wmr_{c}_step", frames, library) for c in CONTROLLERS}
    own_text = {}
    for name, elf in elves.items():
        syms = symbols(elf)
        own_text[name] = sum(
            s for n, (_, s, k) in syms.items() if n.startswith("wmr_") and k in "tT"
        )
    report = Report(
        toolchain_version(),
        f32,
        f64,
        elves,
        sizes,
        doubles,
        frames,
        library,
        functions,
        step_stack,
        own_text,
    )
    if emulate_run:
        try:
            import unicorn  # noqa: F401
        except ImportError:
            report.notes.append("Emulated run skipped: the `unicorn` package is not installed.")
        else:
            elf, binary = link_emulator_image(f32)
            rec = record_closed_loop()
            report.emulation = emulate(rec, elf, binary)
            report.comparison = compare(rec, report.emulation)
    return report


def _yes(flag: bool) -> str:
    return "yes" if flag else "**no**"


def _path(bound: StackBound) -> str:
    return " → ".join(bound.path)


def render(r: Report) -> str:
    lines = [
        "# Firmware: the generated C on a Cortex-M4F",
        "",
        "Generated by `python -m runtime.firmware_report` (numbers depend on the toolchain).",
        "",
        f"Toolchain: `{r.version}`. Flags: `{' '.join(ARM_FLAGS)} -DWMR_FLOAT32 -fstack-usage`",
        f"(plus `{' '.join(SECTION_FLAGS)} -fcallgraph-info=su` for the analysis and the",
        "links). Every `generated/c/wmr_*.c` (not `example_main.c`) compiles with `-Werror`",
        "in float32 and in double"
        + (
            " with no diagnostic at all."
            if not (r.float_objs.warnings + r.double_objs.warnings).strip()
            else ": **diagnostics were printed**."
        ),
        "",
        "## Per controller: a minimal image (float32)",
        "",
        "A `main` that fills a configuration, calls `wmr_<ctrl>_init` and one",
        "`wmr_<ctrl>_step`, linked with newlib-nano (`--specs=nano.specs --specs=nosys.specs",
        "-Wl,--gc-sections -lm`). `.text` includes the C start-up code and the libm functions",
        "used (sinf, cosf, sqrtf); *generated code* is the sum of the `wmr_*` functions.",
        "The worst-case stack is that of `wmr_<ctrl>_step` through all its callees.",
        "",
        "| controller | .text | .data | .bss | generated code | double helpers (`__aeabi_d*`, ...) "
        "| worst-case stack of step |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in CONTROLLERS:
        s, b = r.sizes[name], r.step_stack[name]
        dbl = ", ".join(r.doubles[name]) or "none"
        lines.append(
            f"| {name.upper()} | {s['text']} | {s['data']} | {s['bss']} | {r.own_text[name]} "
            f"| {dbl} | {b.bytes} B{'' if b.complete else ' (incomplete)'} |"
        )
    lines += ["", "Deepest chains:", ""]
    for name in CONTROLLERS:
        lines.append(f"* {name.upper()}: {_path(r.step_stack[name])}")
    lines += [
        "",
        "## Per function (float32)",
        "",
        "Code size from `nm -S`; own frame from `-fstack-usage`; worst case = own frame plus",
        "the deepest chain of callees (call graph from `-fcallgraph-info=su`; library callees'",
        "frames read from the linked ELF's disassembly: push/vpush/sub sp). `static`: the",
        "frame is fixed (no VLA/alloca); no function is recursive.",
        "",
        "| function | code bytes | own frame | kind | worst-case stack | deepest callee chain |",
        "|---|---|---|---|---|---|",
    ]
    for name, size, own, qual, bound in r.functions:
        chain = " → ".join(bound.path[1:]) or "—"
        lines.append(
            f"| `{name}` | {size} | {own} | {qual} | {bound.bytes}"
            f"{'' if bound.complete else ' (incomplete)'} | {chain} |"
        )
    lines += ["", "## Emulated run (Unicorn, Cortex-M4 + FPU)", ""]
    if r.emulation is None or r.comparison is None:
        lines += [*r.notes, ""]
    else:
        e, c = r.emulation, r.comparison
        ins = np.array(e.instructions)
        lines += [
            "The float32 TDROC step (paper formulation, ε = 0.5, the experiment's other",
            "defaults), linked with newlib-nano's libm into a flat image and run in Unicorn",
            "(`UC_CPU_ARM_CORTEX_M4`), on the controller inputs recorded from",
            "`runtime.simulate.run('tdroc', 'paper', lawn mower, float32=True)`. The host",
            "builds replay the same inputs (x86-64 gcc, cffi).",
            "",
            "| quantity | value |",
            "|---|---|",
            f"| steps | {e.steps} |",
            "| instructions per step: mean / min / max | "
            f"{ins.mean():.0f} / {ins.min()} / {ins.max()} |",
            f"| instructions of `wmr_tdroc_init` | {e.init_instructions} |",
            f"| stack high-water mark (measured, incl. harness) | {e.stack_bytes} B |",
            f"| statuses equal (emulated, host float32, host double) | {_yes(c.same_status)} |",
            "| host float32 replay = the recorded closed loop | "
            f"{_yes(c.host_float_reproduces_loop)} |",
            "| torque vs host float32: max / median distance | "
            f"{c.max_ulps} / {c.median_ulps:g} ulp |",
            "| torque vs host float32: max abs difference | "
            f"{c.max_abs_vs_float:.3g} N m = {c.scale_ulps_vs_float:.3g} ulp of the largest "
            "torque |",
            f"| torque vs host double: max abs difference | {c.max_abs_vs_double:.3g} N m |",
            f"| ... relative to the run's largest torque | {c.max_rel_vs_double:.3g} |",
            "",
            "The largest distance in ulps is at a torque near zero, where an ulp is tiny. In",
            "absolute terms the ARM and host float32 torques agree to "
            f"{c.scale_ulps_vs_float:.2g} ulp of the run's",
            f"largest torque ({c.torque_scale:.3g} N m); the libm functions differ (newlib-nano",
            "vs glibc) and the differences carry over from step to step through u(t - h).",
            "",
            "Instructions are counted per executed basic block (Thumb-2 widths decoded), so an",
            "instruction skipped by an IT block still counts; at one instruction per cycle this",
            "is a lower bound on cycles (the FPU's vdiv/vsqrt take 14 cycles each).",
            "",
        ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Cortex-M4 cross-build report")
    parser.add_argument("--out", type=Path, default=DOC)
    parser.add_argument("--no-emulation", action="store_true")
    args = parser.parse_args(argv)
    if not have_toolchain():
        print(f"{ARM_GCC} not found: install gcc-arm-none-eabi libnewlib-arm-none-eabi")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        report = build_report(Path(tmp), emulate_run=not args.no_emulation)
        text = render(report)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
