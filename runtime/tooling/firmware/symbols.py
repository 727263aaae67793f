"""What a linked Cortex-M4 image contains: its symbols with their sizes (``nm -S``), its
``.text``/``.data``/``.bss`` (``size``), and the soft-float double helpers linked in
(there must be none in a float32 image).
"""

from __future__ import annotations

import re
from pathlib import Path

from runtime.tooling.firmware.build import run_tool, tool

# Soft-float double helpers of libgcc (EABI names and their GNU aliases).
DOUBLE_SYMBOL = re.compile(
    r"^(__aeabi_d\w*|__aeabi_[filu]+2d|__aeabi_ul2d|__\w+df[23]|__extendsfdf2|__truncdfsf2)$"
)


def symbols(elf: Path) -> dict[str, tuple[int, int, str]]:
    """name -> (address, size, type) of every symbol with a size."""
    out = {}
    for line in run_tool([str(tool("nm")), "-S", str(elf)]).splitlines():
        parts = line.split()
        if len(parts) == 4:
            out[parts[3]] = (int(parts[0], 16), int(parts[1], 16), parts[2])
    return out


def all_symbol_names(elf: Path) -> list[str]:
    return [line.split()[-1] for line in run_tool([str(tool("nm")), str(elf)]).splitlines() if line]


def double_symbols(elf: Path) -> list[str]:
    """Soft-float double helpers linked into the ELF (must be empty for the float build)."""
    return sorted(s for s in all_symbol_names(elf) if DOUBLE_SYMBOL.match(s))


def elf_sizes(elf: Path) -> dict[str, int]:
    """text, data, bss of ``arm-none-eabi-size`` (Berkeley format)."""
    line = run_tool([str(tool("size")), str(elf)]).splitlines()[1].split()
    return {"text": int(line[0]), "data": int(line[1]), "bss": int(line[2])}


# An input section of the link map: " .rodata.name  0xADDR  0xSIZE  path/file.o" (the name
# on a line of its own when it is long).
_MAP_SECTION = re.compile(r"^ (\.\w+)(?:\.\S*)?\s+0x[0-9a-f]+\s+0x([0-9a-f]+)\s+(\S+)$", re.M)


def generated_rodata(elf: Path) -> int:
    """Bytes of read-only data (constant tables) the generated objects (``wmr_*.o``)
    contribute to the linked ``elf``, from its link map (``elf`` with suffix ``.map``):
    kept input sections only, so what ``--gc-sections`` dropped is not counted."""
    text = elf.with_suffix(".map").read_text()
    kept = text[text.index("Linker script and memory map"):]
    return sum(int(m.group(2), 16) for m in _MAP_SECTION.finditer(kept)
               if m.group(1) == ".rodata" and re.search(r"(^|/)wmr_\w+\.o$", m.group(3)))
