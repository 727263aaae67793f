"""Cortex-M4 code size and stack: our generated C against CasADi's generated C for the same
symbolic functions, float32 and double (issue 6). Writes ``docs/FIRMWARE_VS_CASADI.md``.

    python -m runtime.tooling.firmware.compare_casadi   (part of ``make bench``)

Needs arm-none-eabi-gcc.

Each CasADi function is generated into its own file (``CodeGenerator`` with
``casadi_real`` float or double) so its object's ``.text`` is exactly that function with
its helpers; ours is the function's own symbol (``nm -S``, ``-ffunction-sections``).
Stack: the ``-fstack-usage`` frames of the object's functions summed (an upper bound on
the chain entry → internal evaluation function). Neither calls anything but libm.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from codegen.backends.casadi import generate_c
from codegen.robot_functions import law_specs, model_specs
from modeling.package_paths import default_output
from modeling.robots.drishti.model import robot_model
from runtime.bindings.cbuild import GENERATED_C
from runtime.tooling.firmware.build import ARM_FLAGS, ARM_GCC, have_toolchain
from runtime.tooling.firmware.symbols import DOUBLE_SYMBOL

DOC = default_output("docs/FIRMWARE_VS_CASADI.md")  # ./FIRMWARE_VS_CASADI.md when installed
FUNCTIONS = ("mass_matrix", "bias_forces", "forward_dynamics", "kinematics", "paper_tde",
             "paper_minv_norm", "paper_tdroc_gain", "paper_tdroc_law")


@dataclass(frozen=True)
class Size:
    text: int
    stack: int
    double_helpers: bool


def _compile(src: Path, out: Path, float32: bool, include: Path) -> tuple[Path, Path]:
    flags = [*ARM_FLAGS, "-ffunction-sections", "-fdata-sections", "-fstack-usage",
             f"-I{include}"]
    if float32:
        flags.append("-DWMR_FLOAT32")
    flags = [f for f in flags if f != "-Werror"] if "casadi" in src.name else flags
    obj = out / (src.stem + ("_f" if float32 else "_d") + ".o")
    subprocess.run([ARM_GCC, *flags, "-c", str(src), "-o", str(obj)], check=True,
                   capture_output=True, text=True, cwd=out)
    return obj, obj.with_suffix(".su")


def _symbols(obj: Path) -> dict[str, int]:
    text = subprocess.run(["arm-none-eabi-nm", "-S", "--size-sort", str(obj)], check=True,
                          capture_output=True, text=True).stdout
    out = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[2].lower() == "t":
            out[parts[3]] = int(parts[1], 16)
    return out


def _undefined(obj: Path) -> list[str]:
    text = subprocess.run(["arm-none-eabi-nm", "-u", str(obj)], check=True,
                          capture_output=True, text=True).stdout
    return [line.split()[-1] for line in text.splitlines() if line.strip()]


def _frames(su: Path) -> dict[str, int]:
    frames = {}
    for line in su.read_text().splitlines():
        m = re.match(r".*:(\w+(?:\.\w+)*)\s+(\d+)\s+\w+", line)
        if m:
            frames[m.group(1)] = int(m.group(2))
    return frames


def measure(workdir: Path) -> dict[tuple[str, str, str], Size]:
    specs = {s.name: s for s in (*model_specs(robot_model()), *law_specs(robot_model()))}
    results: dict[tuple[str, str, str], Size] = {}
    for float32 in (True, False):
        precision = "float32" if float32 else "double"
        ours: dict[str, int] = {}
        frames: dict[str, int] = {}
        undefined: list[str] = []
        for module in ("wmr_model", "wmr_laws"):
            obj, su = _compile(GENERATED_C / f"{module}.c", workdir, float32, GENERATED_C)
            ours.update(_symbols(obj))
            frames.update(_frames(su))
            undefined += _undefined(obj)
        has_double = any(DOUBLE_SYMBOL.match(u) for u in undefined)
        for name in FUNCTIONS:
            sym = f"wmr_{name}"
            results[(name, "ours", precision)] = Size(ours[sym], frames.get(sym, 0), has_double)
            cdir = workdir / f"casadi_{name}_{precision}"
            generate_c([specs[name]], cdir, f"casadi_{name}",
                       real="float" if float32 else "double")
            obj, su = _compile(cdir / f"casadi_{name}.c", cdir, False, cdir)
            syms = _symbols(obj)
            results[(name, "casadi", precision)] = Size(
                sum(syms.values()), sum(_frames(su).values()),
                any(DOUBLE_SYMBOL.match(u) for u in _undefined(obj)))
    return results


def render(results: dict[tuple[str, str, str], Size]) -> str:
    lines = [
        "# Cortex-M4: our generated C against CasADi's",
        "",
        "Written by `python -m runtime.tooling.firmware.compare_casadi` (`make bench`). Flags: "
        f"`{' '.join(ARM_FLAGS)}` (`-Werror` dropped for CasADi's C, which warns).",
        "`.text` in bytes; stack = `-fstack-usage` frames (CasADi: entry + internal function);",
        "“double” marks objects that call soft-float double helpers (`__aeabi_d*`).",
        "",
        "| function | precision | ours .text | CasADi .text | ratio | ours stack | CasADi stack "
        "| double helpers (ours / CasADi) |",
        "|---|---|---:|---:|---:|---:|---:|---|",
    ]
    for name in FUNCTIONS:
        for precision in ("float32", "double"):
            o = results[(name, "ours", precision)]
            c = results[(name, "casadi", precision)]
            dh = f"{'yes' if o.double_helpers else 'no'} / {'yes' if c.double_helpers else 'no'}"
            lines.append(
                f"| {name} | {precision} | {o.text} | {c.text} | {o.text / c.text:.2f} "
                f"| {o.stack} | {c.stack} | {dh if precision == 'float32' else '—'} |")
    lines += [
        "",
        "CasADi's `casadi_real float` build still prints double literals and calls `sin`,",
        "`cos` and `sqrt` in double, so on a single-precision FPU it pulls in the soft-float",
        "double helpers; ours uses `sinf`/`cosf`/`sqrtf` and float literals throughout.",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime.tooling.firmware.compare_casadi")
    parser.add_argument("--out", type=Path, default=DOC)
    args = parser.parse_args(argv)
    if not have_toolchain():
        print(f"error: {ARM_GCC} not found (apt-get install gcc-arm-none-eabi)", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        text = render(measure(Path(tmp)))
    args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
