"""The worst-case stack of a function: its own frame (``-fstack-usage``) plus the deepest
chain of callees — generated callees from the call graph of ``-fcallgraph-info``, library
callees (``sinf``, ``memcpy``, ...) from the linked ELF's disassembly (push/vpush/sub sp).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from runtime.tooling.firmware.build import run_tool, tool


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


def compiled_frames(ci_files: Sequence[Path], su_files: Sequence[Path]) -> dict[str, Frame]:
    """The compiled functions' frames: the call graph (``.ci``), each frame's size from
    ``.su`` (authoritative for the frame)."""
    frames = parse_callgraph(ci_files)
    for name, (own, qual) in parse_su(su_files).items():
        if name in frames:
            frames[name].own, frames[name].qualifier = own, qual
        else:
            frames[name] = Frame(name, own, qual)
    return frames


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
    text = run_tool([str(tool("objdump")), "-d", "--no-show-raw-insn", str(elf)])
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
