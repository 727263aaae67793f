"""Cross-build for a Cortex-M4F (``runtime.tooling.firmware``): every generated .c compiles
with ``-Werror`` in float32 and double; the float32 image of each controller links with
newlib-nano and contains no double-precision helper; sizes and worst-case stack; the
float32 TDROC step emulated in Unicorn on a recorded closed loop agrees with the host
builds. Skipped when ``arm-none-eabi-gcc`` (or newlib) is not installed; ``.ci/run``
installs it. About 15 s.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from runtime.tooling.firmware import build
from runtime.tooling.firmware import report as fr
from runtime.tooling.firmware.code_budget import UNCLASSIFIED, budget, part_of
from runtime.tooling.firmware.stack import parse_su
from runtime.tooling.firmware.symbols import all_symbol_names, double_symbols

pytestmark = pytest.mark.skipif(
    not build.have_toolchain() or not build.have_newlib(),
    reason="arm-none-eabi-gcc with newlib not installed "
    "(apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi; .ci/run does)",
)
HAVE_UNICORN = importlib.util.find_spec("unicorn") is not None
STACK_BUDGET = 2048  # bytes for a controller step, through every callee
GENERATED_BUDGET = 16 * 1024  # bytes of generated code in one controller image


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> fr.Report:
    return fr.build_report(tmp_path_factory.mktemp("arm"), emulate_run=HAVE_UNICORN)


def test_every_generated_file_compiles_without_diagnostics(report: fr.Report) -> None:
    names = {p.stem for p in build.generated_sources()}
    assert "example_main" not in names and {"wmr_model", "wmr_tdroc"} <= names
    for objs in (report.float_objs, report.double_objs):
        assert {p.stem for p in objs.objects} == names
        assert all(p.stat().st_size > 0 for p in objs.objects)
        assert objs.warnings.strip() == ""
        assert len(objs.su) == len(names)


@pytest.mark.parametrize("name", build.CONTROLLERS)
def test_float_image_has_no_double_arithmetic(report: fr.Report, name: str) -> None:
    elf = report.elves[name]
    assert report.doubles[name] == [], report.doubles[name]
    syms = all_symbol_names(elf)
    assert f"wmr_{name}_step" in syms and f"wmr_{name}_init" in syms
    assert not any(s.startswith("__aeabi_d") for s in syms)
    sizes = report.sizes[name]
    assert sizes["text"] > report.own_text[name] > 1000
    assert report.own_text[name] < GENERATED_BUDGET


def test_generated_constants_are_the_kept_tables(report: fr.Report) -> None:
    """The link map's count of the generated read-only data: at least the nominal check's
    bound table (one float per nominal parameter, always linked by _init), at most every
    .rodata section of the generated objects (some are dropped by --gc-sections)."""
    types = build.GENERATED_C.joinpath("wmr_types.h").read_text()
    params = types[types.index("typedef struct {"):types.index("} wmr_params_t;")]
    n_params = params.count("wmr_real_t ")
    in_objects = 0
    for obj in report.float_objs.objects:
        out = build.run_tool([str(build.tool("size")), "-A", str(obj)])
        in_objects += sum(int(line.split()[1]) for line in out.splitlines()
                          if line.startswith(".rodata"))
    for name in build.CONTROLLERS:
        assert 4 * n_params <= report.own_rodata[name] <= in_objects, name



def test_every_generated_function_has_a_part_of_the_budget(report: fr.Report) -> None:
    """docs/FIRMWARE.md's code budget: each generated function of every image (the four
    controllers, the formulation-only TDROC images) in exactly the part its name says, the
    parts summing to the image's generated code."""
    images = {**report.own_functions,
              **{f"tdroc/{form}": img.own_functions for form, img in report.only.items()},
              **{f"tdroc/frozen/{form}": img.own_functions
                 for form, img in report.frozen.items()}}
    for image, functions in images.items():
        unclassified = [f for f in functions if part_of(f) == UNCLASSIFIED]
        assert not unclassified, (image, unclassified)
        assert sum(budget(functions).values()) == sum(functions.values()), image
    # The parts are what they say: the law and the estimator are control math, the
    # per-parameter checks configuration checks, whatever the controller.
    assert part_of("wmr_minimal_tdroc_law") == part_of("wmr_paper_tde_trig") == \
        "control law and estimators (from SymPy)"
    assert part_of("wmr_asmc_check_config_detail") == part_of("wmr_check_nominal") == \
        "configuration checks"
    assert part_of("wmr_tdroc_config_unchanged") == "configuration comparison"
    assert part_of("wmr_norm5") == part_of("wmr_norm_scaled") == \
        "control law and estimators (from SymPy)"
    assert part_of("wmr_paper_minv_norm") == "configuration-derived data, init, reset"
    assert part_of("wmr_something_new") == UNCLASSIFIED

def test_the_double_check_catches_double_arithmetic(tmp_path: Path) -> None:
    """The symbol check is not vacuous: a float build that uses a double does link one."""
    src = tmp_path / "d.c"
    src.write_text(
        "volatile double x = 1.5; volatile float y;\n"
        "int main(void) { y = (float)(x * x); return 0; }\n"
    )
    elf = tmp_path / "d.elf"
    build.run_tool(
        [
            build.ARM_GCC,
            *build.ARM_FLAGS,
            str(src),
            "--specs=nano.specs",
            "--specs=nosys.specs",
            "-o",
            str(elf),
        ]
    )
    assert "__aeabi_dmul" in double_symbols(elf)


def test_stack_usage_is_static_and_bounded(report: fr.Report) -> None:
    assert report.functions
    for name, size, own, qual, bound in report.functions:
        assert qual == "static", (name, qual)  # no VLA, no alloca
        assert bound.complete, (name, bound.path)  # every callee known, no recursion
        assert size > 0 and bound.bytes >= own
    for name, bound in report.step_stack.items():
        assert bound.complete and bound.bytes <= STACK_BUDGET, (name, bound)
        assert bound.path[0] == f"wmr_{name}_step"


def test_elf_frames_agree_with_stack_usage_files(report: fr.Report) -> None:
    """The disassembly reader (used for library callees) gives the compiler's own numbers
    for every generated function in the images."""
    su = parse_su(report.float_objs.su)
    checked = 0
    for name, (own, _) in su.items():
        frame = report.library.get(name)
        if frame is not None:
            assert frame.own == own, (name, frame.own, own)
            checked += 1
    assert checked >= 20


@pytest.mark.skipif(not HAVE_UNICORN, reason="unicorn (PyPI) not installed")
def test_emulated_tdroc_matches_the_host_builds(report: fr.Report) -> None:
    emu, cmp = report.emulation, report.comparison
    assert emu is not None and cmp is not None
    assert emu.steps == 601  # 60 s lawn mower at h = 0.1 s
    assert cmp.same_status and cmp.host_float_reproduces_loop
    # ARM float32 vs host float32 (different libm, measured 1.25): within 4 ulp of the
    # run's largest torque.
    assert cmp.scale_ulps_vs_float <= 4.0, cmp
    # ... and vs the host double build, within float precision of the torque scale.
    assert cmp.max_rel_vs_double <= 1e-5, cmp
    assert 1000 < max(emu.instructions) < 10_000
    # The measured stack (harness included) stays under the static bound of the step
    # plus the harness's own frame.
    assert 0 < emu.stack_bytes <= report.step_stack["tdroc"].bytes + 64


def test_frozen_image_meets_the_firmware_goals(report: fr.Report) -> None:
    """Issue 12's Cortex-M4 goals for a TDROC-only image, met by the build with the
    configuration compiled in (`wmr freeze`) and the minimal formulation: <= 3 KB of
    generated code, <= 512 B of step stack through every callee, no double helpers; and
    that build has none of the configuration checks, comparison or derivation."""
    minimal = report.frozen["MINIMAL"]
    assert minimal.own_text <= 3 * 1024, minimal.own_functions
    assert minimal.step_stack.complete and minimal.step_stack.bytes <= 512
    assert not minimal.doubles
    for img in report.frozen.values():
        parts = budget(img.own_functions)
        assert parts["configuration checks"] == parts["configuration comparison"] == 0
        assert not any(name.endswith(("_minv_norm", "controller_p", "check_config_detail"))
                       for name in img.own_functions)
    # Freezing removes code and adds only the configuration and state as constants.
    for form, img in report.frozen.items():
        assert img.own_text < report.only[form].own_text
        assert img.own_rodata - report.only[form].own_rodata <= 512


@pytest.mark.skipif(not HAVE_UNICORN, reason="unicorn (PyPI) not installed")
def test_emulated_frozen_images_match_the_run_time_builds(report: fr.Report) -> None:
    """The frozen images run the recorded closed loops to the same statuses and the same
    torques, bit for bit, as the run-time builds, within 1,500 instructions per step."""
    paper, minimal = report.frozen["PAPER"].emulation, report.frozen["MINIMAL"].emulation
    run_time_minimal = report.only["MINIMAL"].emulation
    assert paper is not None and minimal is not None and run_time_minimal is not None
    assert report.emulation is not None
    assert paper.status == report.emulation.status and paper.tau == report.emulation.tau
    assert minimal.status == report.only_minimal_recorded_status
    assert minimal.tau == run_time_minimal.tau
    assert max(minimal.instructions) <= 1500 and max(paper.instructions) <= 1500


def test_report_renders(report: fr.Report) -> None:
    text = fr.render(report)
    for name in build.CONTROLLERS:
        assert f"| {name.upper()} |" in text
    assert ("instructions per step" in text) == HAVE_UNICORN


def test_committed_doc_matches_this_toolchain(report: fr.Report) -> None:
    """docs/FIRMWARE.md is this report's output (compared up to the emulation section,
    whose host-float numbers depend on the host's libm), if written by this toolchain."""
    if not fr.DOC.exists():
        pytest.fail("docs/FIRMWARE.md missing: run `python -m runtime.tooling.firmware.report`")
    committed = fr.DOC.read_text()
    if report.version not in committed:
        pytest.skip(f"docs/FIRMWARE.md was written by another toolchain than {report.version}")
    marker = "## Emulated run"
    assert committed.split(marker)[0] == fr.render(report).split(marker)[0], (
        "docs/FIRMWARE.md is stale: run `python -m runtime.tooling.firmware.report`"
    )
