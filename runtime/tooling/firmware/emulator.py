"""The float32 TDROC step in the Unicorn emulator (Cortex-M4 with FPU): a C harness
exchanging inputs and outputs through a ``wmr_io`` struct, linked into a flat image, and
an :class:`Emulator` that calls its functions, counts the instructions executed and
measures the stack's high-water mark.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from modeling.robots.drishti.parameters import LUMPED
from runtime.bindings.cbuild import GENERATED_C
from runtime.tooling.firmware.build import (
    ARM_FLAGS,
    ARM_GCC,
    SECTION_FLAGS,
    Objects,
    frozen_define,
    run_tool,
    tool,
)
from runtime.tooling.firmware.symbols import symbols

EMU_BASE = 0x20000000
EMU_SIZE = 1 << 20
EMU_STACK = 0x4000  # bytes of stack below EMU_BASE + EMU_SIZE
STACK_FILL = 0xCD
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
PARAM_FIELDS = tuple(p.c_field for p in LUMPED)  # wmr_params_t's members, in order


def io_offsets() -> dict[str, tuple[int, int, str]]:
    """field -> (byte offset, count, struct code) of the harness's ``wmr_io``."""
    out, offset = {}, 0
    for name, count, code in IO_FIELDS:
        out[name] = (offset, count, code)
        offset += 4 * count
    return out


def harness_source(frozen: bool = False) -> str:
    """The harness; ``frozen``: for a build with the configuration compiled in, which
    harness_init and harness_step pass instead of the one filled from ``wmr_io``."""
    decl = "\n".join(
        f"    {'float' if c == 'f' else 'int'} {n}{f'[{k}]' if k > 1 else ''};"
        for n, k, c in IO_FIELDS
    )
    params = "\n".join(
        f"    cfg.nominal.{p} = wmr_io.params[{i}];" for i, p in enumerate(PARAM_FIELDS)
    )
    config = "&wmr_tdroc_frozen_config" if frozen else "&cfg"
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
    wmr_io.status = wmr_tdroc_init(&state, {config});
}}

void harness_step(void)
{{
    wmr_io.status = wmr_tdroc_step(&state, {config}, wmr_io.in, wmr_io.in + 5, wmr_io.in + 10,
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
    harness.write_text(harness_source(frozen_define("tdroc") in objs.defines))
    script = objs.dir / "emu.ld"
    script.write_text(LINKER_SCRIPT)
    elf, binary = objs.dir / "emu.elf", objs.dir / "emu.bin"
    run_tool(
        [
            ARM_GCC,
            *ARM_FLAGS,
            *SECTION_FLAGS,
            "-DWMR_FLOAT32",
            *objs.defines,
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
    run_tool([str(tool("objcopy")), "-O", "binary", str(elf), str(binary)])
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
        for line in run_tool([str(tool("nm")), str(elf)]).splitlines():
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
