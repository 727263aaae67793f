"""``python -m runtime.tooling.firmware.report [--out docs/FIRMWARE.md] [--no-emulation]``:
build, measure and (if ``unicorn`` is installed) emulate, then write ``docs/FIRMWARE.md``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from modeling.package_paths import default_output
from runtime.commands.output_folder import OutputFolderError, writable_file
from runtime.tooling.firmware.build import (
    ARM_FLAGS,
    ARM_GCC,
    CONTROLLERS,
    SECTION_FLAGS,
    Objects,
    compile_generated,
    frozen_define,
    have_toolchain,
    link_controller,
    toolchain_version,
)
from runtime.tooling.firmware.code_budget import PARTS, UNCLASSIFIED, budget
from runtime.tooling.firmware.emulated_run import (
    Comparison,
    EmulationResult,
    compare,
    emulate,
    record_closed_loop,
)
from runtime.tooling.firmware.emulator import link_emulator_image
from runtime.tooling.firmware.stack import (
    Frame,
    StackBound,
    compiled_frames,
    elf_frames,
    worst_stack,
)
from runtime.tooling.firmware.symbols import double_symbols, elf_sizes, generated_rodata, symbols

DOC = default_output("docs/FIRMWARE.md")  # ./FIRMWARE.md when installed
EMULATED_EPS = 0.5  # the boundary layer of the emulated run (record_closed_loop's default)


@dataclass(frozen=True)
class OnlyImage:
    """The TDROC image of a build with one formulation compiled in
    (``-DWMR_FORMULATION_ONLY=WMR_FORMULATION_<formulation>``), or with its whole
    configuration compiled in (``wmr freeze``, -DWMR_TDROC_FROZEN)."""

    sizes: dict[str, int]
    own_functions: dict[str, int]  # generated function -> code bytes
    own_rodata: int  # the generated objects' constant tables
    doubles: list[str]
    step_stack: StackBound
    objects: Objects
    emulation: EmulationResult | None = None  # the recorded run (paper) on this build

    @property
    def own_text(self) -> int:
        return sum(self.own_functions.values())


def generated_functions(elf: Path) -> dict[str, int]:
    """The generated functions (``wmr_*``) linked into ``elf`` and their code bytes."""
    return {n: s for n, (_, s, k) in symbols(elf).items() if n.startswith("wmr_") and k in "tT"}


def _measured_image(objs: Objects, formulation: str) -> OnlyImage:
    elf = link_controller(objs, "tdroc", formulation)
    frames = compiled_frames(objs.ci, objs.su)
    return OnlyImage(elf_sizes(elf), generated_functions(elf), generated_rodata(elf),
                     double_symbols(elf),
                     worst_stack("wmr_tdroc_step", frames, elf_frames(elf)), objs)


def formulation_only_image(work: Path, formulation: str) -> OnlyImage:
    """Compile (float32) with one formulation only, link the TDROC image, measure it."""
    objs = compile_generated(
        work / f"float32_{formulation.lower()}", True,
        defines=(f"-DWMR_FORMULATION_ONLY=WMR_FORMULATION_{formulation}",),
    )
    return _measured_image(objs, formulation)


def frozen_config_header(folder: Path, formulation: str) -> Path:
    """``wmr freeze`` of the emulated run's TDROC configuration (:data:`EMULATED_EPS`, the
    experiment's other defaults) for float32, into ``folder``."""
    from runtime.bindings import cbuild
    from runtime.bindings.config import controller_config
    from runtime.bindings.generated import load_robot_code
    from runtime.experiment.settings import Experiment
    from runtime.freeze.header import freeze

    code = load_robot_code("")
    lib = cbuild.build(True)
    exp = Experiment()
    exp = replace(exp, controller=replace(exp.controller, eps=EMULATED_EPS))
    config = controller_config(lib, code, "tdroc", formulation.lower(), code.params, exp)
    frozen = freeze(lib, code, "tdroc", config,
                    [f"Made by: runtime.tooling.firmware.report ({formulation.lower()}, "
                     f"eps = {EMULATED_EPS})"])
    folder.mkdir(parents=True, exist_ok=True)
    header = folder / frozen.filename
    header.write_text(frozen.text)
    return header


def frozen_image(work: Path, formulation: str) -> OnlyImage:
    """Compile (float32) with the TDROC configuration compiled in, link, measure."""
    folder = work / f"float32_frozen_{formulation.lower()}"
    header = frozen_config_header(folder, formulation)
    objs = compile_generated(folder, True,
                             defines=(frozen_define("tdroc"), f"-I{header.parent}"))
    return _measured_image(objs, formulation)


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
    own_functions: dict[str, dict[str, int]]  # controller -> its image's generated functions
    own_rodata: dict[str, int]
    only: dict[str, OnlyImage] = field(default_factory=dict)  # formulation -> TDROC image
    frozen: dict[str, OnlyImage] = field(default_factory=dict)  # formulation -> frozen image
    only_minimal_recorded_status: list[int] = field(default_factory=list)
    emulation: EmulationResult | None = None
    comparison: Comparison | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def own_text(self) -> dict[str, int]:
        return {name: sum(f.values()) for name, f in self.own_functions.items()}


def build_report(work: Path, emulate_run: bool = True) -> Report:
    """Compile, link, analyse (and emulate) in ``work``."""
    f32 = compile_generated(work / "float32", True)
    f64 = compile_generated(work / "double", False)
    elves = {name: link_controller(f32, name) for name in CONTROLLERS}
    sizes = {name: elf_sizes(elf) for name, elf in elves.items()}
    doubles = {name: double_symbols(elf) for name, elf in elves.items()}
    frames = compiled_frames(f32.ci, f32.su)
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
        {name: generated_functions(elf) for name, elf in elves.items()},
        {name: generated_rodata(elf) for name, elf in elves.items()},
    )
    report.only = {f: formulation_only_image(work, f) for f in ("PAPER", "MINIMAL")}
    report.frozen = {f: frozen_image(work, f) for f in ("PAPER", "MINIMAL")}
    if emulate_run:
        try:
            import unicorn  # noqa: F401
        except ImportError:
            report.notes.append("Emulated run skipped: the `unicorn` package is not installed.")
        else:
            elf, binary = link_emulator_image(f32)
            rec = record_closed_loop(eps=EMULATED_EPS)
            report.emulation = emulate(rec, elf, binary)
            report.comparison = compare(rec, report.emulation)
            paper = report.only["PAPER"]
            elf, binary = link_emulator_image(paper.objects)
            report.only["PAPER"] = replace(paper, emulation=emulate(rec, elf, binary))
            # The minimal formulation's own closed loop, on the minimal-only build.
            minimal = report.only["MINIMAL"]
            elf, binary = link_emulator_image(minimal.objects)
            rec_min = record_closed_loop(formulation="minimal", eps=EMULATED_EPS)
            report.only["MINIMAL"] = replace(minimal, emulation=emulate(rec_min, elf, binary))
            report.only_minimal_recorded_status = rec_min.status
            for form, recording in (("PAPER", rec), ("MINIMAL", rec_min)):
                img = report.frozen[form]
                elf, binary = link_emulator_image(img.objects)
                report.frozen[form] = replace(img, emulation=emulate(recording, elf, binary))
    return report


def _yes(flag: bool) -> str:
    return "yes" if flag else "**no**"


def _path(bound: StackBound) -> str:
    return " → ".join(bound.path)


def _budget_lines(r: Report) -> list[str]:
    """The TDROC images' generated code per part of the contract (code_budget)."""
    images = {"both formulations": r.own_functions["tdroc"]}
    images.update({f"{form.lower()} only": img.own_functions for form, img in r.only.items()})
    images.update({f"{form.lower()}, frozen": img.own_functions
                   for form, img in r.frozen.items()})
    budgets = {name: budget(functions) for name, functions in images.items()}
    when = {p.name: p.when for p in PARTS}
    parts = [*when, *([UNCLASSIFIED] if any(UNCLASSIFIED in b for b in budgets.values())
                      else [])]
    lines = [
        "",
        "### Where the TDROC image's generated code goes",
        "",
        "The generated functions of each TDROC image above, by the part of the contract they",
        "implement (`runtime/tooling/firmware/code_budget.py`; bytes of code). A function",
        "gcc inlines is counted where it is inlined: the configuration comparison, a",
        "`static` function of each controller, is part of its step when it shows 0.",
        "",
        "| part | runs | " + " | ".join(budgets) + " |",
        "|---|---|" + "---|" * len(budgets),
    ]
    for part in parts:
        lines.append(f"| {part} | {when.get(part, '?')} | "
                     + " | ".join(str(b.get(part, 0)) for b in budgets.values()) + " |")
    lines.append("| **total** | | "
                 + " | ".join(f"**{sum(b.values())}**" for b in budgets.values()) + " |")
    return lines


def _image_row(label: str, img: OnlyImage) -> str:
    return (f"| {label} | {img.sizes['text']} | {img.sizes['data']} | {img.sizes['bss']} | "
            f"{img.own_text} | {img.own_rodata} | {', '.join(img.doubles) or 'none'} | "
            f"{img.step_stack.bytes} B{'' if img.step_stack.complete else ' (incomplete)'} |")


def _frozen_emulation_rows(r: Report, e: EmulationResult) -> list[str]:
    """The frozen images' emulated runs: paper against the run-time image's, minimal
    against the host float32 closed loop and the minimal-only image's torques."""
    rows = []
    mo = r.only["MINIMAL"].emulation if "MINIMAL" in r.only else None
    for form, img in r.frozen.items():
        fe = img.emulation
        if fe is None:
            continue
        ins = f"{np.mean(fe.instructions):.0f} / {min(fe.instructions)} / {max(fe.instructions)}"
        if form == "PAPER":
            same = (f"statuses equal: {_yes(fe.status == e.status)}, torques equal: "
                    f"{_yes(fe.tau == e.tau)}")
        else:
            same = (f"statuses = host float32 closed loop: "
                    f"{_yes(fe.status == r.only_minimal_recorded_status)}, torques = the "
                    f"minimal-only build's: {_yes(mo is not None and fe.tau == mo.tau)}")
        rows.append(f"| {form.lower()} formulation, configuration frozen (`wmr freeze`): "
                    f"mean / min / max | {ins} ({same}) |")
        rows.append(f"| ... instructions of its `wmr_tdroc_init` | {fe.init_instructions} |")
    return rows


def render(r: Report) -> str:
    lines = [
        "# Firmware: the generated C on a Cortex-M4F",
        "",
        "Generated by `python -m runtime.tooling.firmware.report` (numbers depend on the "
        "toolchain).",
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
        "## The API contract",
        "",
        f"Per controller (`<ctrl>` = {', '.join(CONTROLLERS)}), all in `wmr_<ctrl>.h`:",
        "",
        "* `wmr_<ctrl>_init(state, config)`: validates the configuration against the",
        "  plausibility bounds of `wmr_controller.h` (`WMR_H_MIN`..`WMR_H_MAX`,",
        "  `WMR_GAIN_MIN`..`WMR_GAIN_MAX`, `WMR_TORQUE_LIMIT_MAX`, `WMR_NOMINAL_FACTOR`;",
        "  docs/BAD_INPUT.md) and fills the caller-owned state, keeping a copy of the",
        "  configuration; on error nothing is written.",
        "* `wmr_<ctrl>_step(state, config, q, qdot, q_des, qdot_des, qddot_des, tau)`:",
        "  commit-on-success: on any error neither the state nor tau is written (the step",
        "  computes into locals and writes the state last). Each step compares the",
        "  configuration with that copy, value by value and bit for bit, and computes from",
        "  the copy; only one that differs in any bit is validated again: an",
        "  invalid one returns its field's error, a valid one `WMR_ERR_CONFIG_CHANGED`",
        "  (-19); `_init` adopts a new one. Adaptive gains are capped at `WMR_GAIN_MAX`; the",
        "  step counter is a saturating `uint32_t`.",
        "* Formulation: chosen by `config->formulation` (both linked), or at compile time",
        "  with `-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER` (or `_MINIMAL`): then only",
        "  that one is accepted (the other is `WMR_ERR_BAD_FORMULATION`) and linked.",
        "* Configuration compiled in: `wmr freeze` writes `wmr_<ctrl>_frozen.h` (a",
        "  configuration `_check_config` accepted and the state `_init` left, both run on the",
        "  host in the firmware's precision); built with `-DWMR_<CTRL>_FROZEN`, `_init` and",
        "  the step take `&wmr_<ctrl>_frozen_config` only (another pointer:",
        "  `WMR_ERR_CONFIG_CHANGED`, nothing written) and neither validate nor compare it",
        "  (the state keeps no copy). The statuses for inputs, the outputs and the state",
        "  are those of the run-time build given that configuration.",
        "* `wmr_<ctrl>_step_detail(..., tau, detail)` and",
        "  `wmr_<ctrl>_check_config_detail(config, detail)`: the same, and a",
        "  `wmr_error_detail_t {status, field, index}` in the caller's `detail` (may be NULL)",
        "  naming the input or field (`wmr_field_t`) and the entry that was bad. Only",
        "  `*detail` is written on error; the status codes are unchanged.",
        "* `wmr_<ctrl>_reset(state)`: an initialised state back to what `_init` left",
        "  (history, estimates, count, adapted gain), configuration-derived data kept.",
        "* History: a step writes the rows of the history (q(t-h), qdot(t-h), qdot(t-2h),",
        "  u(t-h), u(t-2h)) and of H1hat that its formulation's steps read, and no other: all",
        "  five in the paper formulation; in the minimal one the controlled rows 4-5, H1hat's",
        "  first two (its estimate, packed) and no row of q(t-h), which its (17) does not",
        "  read. The other rows stay as `_init` left them",
        "  (zero): the formulation cannot change without `_init`.",
        "* Traction (optional, after a step; `wmr_model.h`): "
        "`wmr_wheel_contact_forces(p, q,",
        "  wheel_rates, tau, longitudinal, lateral)` (the multipliers of (9); tau: the net",
        "  torques), then `wmr_traction_check(longitudinal, lateral, mu, loads, shares,",
        "  margins)` returns `WMR_WARN_TRACTION` (2, not an error) when a driven wheel's",
        "  margin mu N - sqrt(Fx^2 + (share Fy)^2) on a friction circle is <= 0 (loads,",
        "  shares: the static split of `runtime/sim/slip_monitor.py`),",
        "  `WMR_ERR_BAD_TRACTION` for mu or a load <= 0, and the model functions' statuses;",
        "  like them it writes nothing unless `WMR_OK`: `wmr_traction_margins` writes the",
        "  margins whatever their sign.",
        "* float32 certificate conditions (optional, after a TDROC or ASMC step):",
        "  `wmr_<ctrl>_within_certificate(state)` returns `WMR_OK` when the switching gain the",
        "  step used (and for TDROC, when (25) computed it, ||Mhat^-1|| and the window's",
        "  difference norms) is in the boxes its certified float32 torque bound is stated over",
        "  (`WMR_<CTRL>_CERT_*`, docs/FLOAT32.md), `WMR_WARN_UNCERTIFIED` (3, not an error)",
        "  when not, `WMR_ERR_NOT_INITIALISED` for a state `_init` did not make. It reads the",
        "  state only; no step calls it, so the step images below do not link it.",
        "* Inputs a function does not read: step functions validate every entry of every",
        "  input; a generated model/law function checks the entries it reads and ignores",
        "  the others, as its header lists.",
        "* sin and cos: the TDC and TDROC steps take both of an angle from",
        "  `wmr_sincos_checked` (`wmr_types.h`: one argument reduction, exact to twice the",
        "  steps' input bound 1e6, within 2 ulp in float32; through `fmaf`, one `vfms` here),",
        "  so they link no libm trigonometry; the ROC and ASMC laws and the model functions",
        "  call `wmr_sin`/`wmr_cos`: the same reduction within its bound, `sinf`/`cosf` beyond.",
        "  `-DWMR_LIBM_TRIG` makes every one call libm.",
        "* float32 accuracy: `python -m codegen.backends.c.certify` proves, for every",
        "  generated function of Drishti and the trailer over a declared input box, a bound on",
        "  |float32 - exact| per output and that no intermediate overflows or is NaN (or names",
        "  the operation it could not prove), and bounds each controller step's torque against",
        "  tau_max; the method, the boxes and the numbers (with the largest errors a search found)",
        "  are in docs/FLOAT32.md, and each generated header states its function's result.",
        "",
        "## Per controller: a minimal image (float32)",
        "",
        "A `main` that fills a configuration, calls `wmr_<ctrl>_init` and one",
        "`wmr_<ctrl>_step`, linked with newlib-nano (`--specs=nano.specs --specs=nosys.specs",
        "-Wl,--gc-sections -lm`). `.text` includes the C start-up code and the libm functions",
        "used (sinf, cosf, sqrtf); *generated code* is the sum of the `wmr_*` functions,",
        "*generated constants* the read-only data (tables) of the generated objects linked in.",
        "The worst-case stack is that of `wmr_<ctrl>_step` through all its callees.",
        "",
        "| controller | .text | .data | .bss | generated code | generated constants "
        "| double helpers (`__aeabi_d*`, ...) | worst-case stack of step |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in CONTROLLERS:
        s, b = r.sizes[name], r.step_stack[name]
        dbl = ", ".join(r.doubles[name]) or "none"
        lines.append(
            f"| {name.upper()} | {s['text']} | {s['data']} | {s['bss']} | {r.own_text[name]} "
            f"| {r.own_rodata[name]} | {dbl} | {b.bytes} B{'' if b.complete else ' (incomplete)'} |"
        )
    lines += ["", "Deepest chains:", ""]
    for name in CONTROLLERS:
        lines.append(f"* {name.upper()}: {_path(r.step_stack[name])}")
    lines += [
        "",
        "## TDROC alone, one formulation chosen at compile time (float32)",
        "",
        "The same image built with `-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER` (or",
        "`_MINIMAL`): the controllers accept that formulation only (the other is",
        "`WMR_ERR_BAD_FORMULATION`) and the other one's kernels are not linked. Without the",
        "define (the rows above) both are linked and `config->formulation` chooses.",
        "",
        "| formulation | .text | .data | .bss | generated code | generated constants "
        "| double helpers | worst-case stack of step |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [_image_row(f"{form.lower()} only", img) for form, img in r.only.items()]
    lines += [
        "",
        "## TDROC with its configuration compiled in (`wmr freeze`, float32)",
        "",
        "`wmr freeze` validates a configuration with `wmr_tdroc_check_config` and runs",
        "`wmr_tdroc_init` on the host, in the firmware's precision, and writes both as",
        "`wmr_tdroc_frozen.h`. Built with `-DWMR_TDROC_FROZEN`, `_init` copies that state and",
        "a step only checks that it was given `&wmr_tdroc_frozen_config` (any other pointer:",
        "`WMR_ERR_CONFIG_CHANGED`), reading the configuration as constants: no configuration",
        "checks, comparison or derivation (P, weights, ‖M̂⁻¹‖) in the image, and the other",
        "formulation folded away. The configuration is the emulated run's "
        f"(ε = {EMULATED_EPS}).",
        "The constants column includes the frozen configuration and state.",
        "",
        "| formulation | .text | .data | .bss | generated code | generated constants "
        "| double helpers | worst-case stack of step |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [_image_row(f"{form.lower()}, frozen", img) for form, img in r.frozen.items()]
    lines += _budget_lines(r)
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
            "`runtime.sim.loop.run(drishti, 'tdroc', 'paper', lawn mower, float32=True)`. The host",
            "builds replay the same inputs (x86-64 gcc, cffi).",
            "",
            "| quantity | value |",
            "|---|---|",
            f"| steps | {e.steps} |",
            "| instructions per step: mean / min / max | "
            f"{ins.mean():.0f} / {ins.min()} / {ins.max()} |",
            *(
                [
                    "| ... built with `-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER`: mean / "
                    f"min / max | {np.mean(po.instructions):.0f} / {min(po.instructions)} / "
                    f"{max(po.instructions)} (statuses equal: "
                    f"{_yes(po.status == e.status)}, torques equal: {_yes(po.tau == e.tau)}) |"
                ]
                if (po := (r.only["PAPER"].emulation if "PAPER" in r.only else None))
                else []
            ),
            *(
                [
                    "| minimal formulation's closed loop on the `-DWMR_FORMULATION_ONLY="
                    "WMR_FORMULATION_MINIMAL` build: mean / min / max | "
                    f"{np.mean(mo.instructions):.0f} / {min(mo.instructions)} / "
                    f"{max(mo.instructions)} (statuses = host float32 closed loop: "
                    f"{_yes(mo.status == r.only_minimal_recorded_status)}) |"
                ]
                if (mo := (r.only["MINIMAL"].emulation if "MINIMAL" in r.only else None))
                else []
            ),
            *_frozen_emulation_rows(r, e),
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
            *(
                [
                    "The ARM and host float32 torques are bit for bit the same: the step's sin and",
                    "cos are the generated `wmr_sincos_checked` (no libm call), and every other",
                    "operation is IEEE single precision on both.",
                ]
                if c.max_ulps == 0 else [
                    "The largest distance in ulps is at a torque near zero, where an ulp is tiny. "
                    "In",
                    "absolute terms the ARM and host float32 torques agree to "
                    f"{c.scale_ulps_vs_float:.2g} ulp of the run's",
                    f"largest torque ({c.torque_scale:.3g} N m); libm functions differ "
                    "(newlib-nano",
                    "vs glibc) and the differences carry over from step to step through u(t - h).",
                ]
            ),
            "",
            "Instructions are counted per executed basic block (Thumb-2 widths decoded), so an",
            "instruction skipped by an IT block still counts; at one instruction per cycle this",
            "is a lower bound on cycles (the FPU's vdiv/vsqrt take 14 cycles each).",
            "",
        ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr firmware",
        description="Cortex-M4 cross-build report of the generated controllers: code size, "
        "worst-case stack, emulated instructions per step (needs arm-none-eabi-gcc).",
    )
    parser.add_argument(
        "--out", type=Path, default=DOC,
        help="report file (default: docs/FIRMWARE.md of a source checkout, ./FIRMWARE.md "
        "when installed)",
    )  # fmt: skip
    parser.add_argument(
        "--no-emulation", action="store_true", help="skip counting instructions in the emulator"
    )
    args = parser.parse_args(argv)
    if not have_toolchain():
        print(f"error: {ARM_GCC} not found: install gcc-arm-none-eabi libnewlib-arm-none-eabi",
              file=sys.stderr)
        return 2
    try:
        args.out = writable_file(args.out)
    except OutputFolderError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        report = build_report(Path(tmp), emulate_run=not args.no_emulation)
        text = render(report)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
