"""Cross-building the generated C for a Cortex-M4F: the ``arm-none-eabi`` toolchain, every
generated ``wmr_*.c`` compiled with :data:`ARM_FLAGS` (float32 or double, with stack-usage
and call-graph files), and a minimal firmware image per controller linked with newlib-nano.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from runtime.bindings.cbuild import GENERATED_C
from runtime.bindings.generated import load_robot_code
from runtime.bindings.generated import robot as generated_robot

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
# The controllers generated for the default robot, as its robot.py exports the registry.
CONTROLLERS = load_robot_code("").controller_names


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


def run_tool(cmd: Sequence[str], cwd: Path | None = None) -> str:
    proc = subprocess.run(list(cmd), capture_output=True, text=True, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stdout}{proc.stderr}")
    return proc.stdout


def generated_sources() -> list[Path]:
    """Every generated .c except example_main.c."""
    return sorted(GENERATED_C.glob("wmr_*.c"))


def toolchain_version() -> str:
    return run_tool([ARM_GCC, "--version"]).splitlines()[0]


@dataclass(frozen=True)
class Objects:
    """Objects of one precision with their stack-usage (.su) and call-graph (.ci) files."""

    dir: Path
    float32: bool
    objects: tuple[Path, ...]
    su: tuple[Path, ...]
    ci: tuple[Path, ...]
    warnings: str  # compiler output (empty: no diagnostics at all)
    defines: tuple[str, ...] = ()  # extra -D flags the objects were compiled with


def compile_generated(out: Path, float32: bool, callgraph: bool | None = None,
                      defines: Sequence[str] = ()) -> Objects:
    """Compile each generated .c with ARM_FLAGS (+ -DWMR_FLOAT32, + ``defines`` such as
    ``-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER``) into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    callgraph = supports_callgraph_info() if callgraph is None else callgraph
    flags = [*ARM_FLAGS, *SECTION_FLAGS, "-fstack-usage", f"-I{GENERATED_C}", *defines]
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
    return Objects(out, float32, tuple(objs), tuple(su), tuple(ci), "".join(diagnostics),
                   tuple(defines))


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
    config.formulation = {formulation};
    for (i = 0; i < 5; ++i) {{
{vectors}
        q[i] = sensor;
        qdot[i] = sensor;
        q_des[i] = sensor;
        qdot_des[i] = sensor;
        qddot_des[i] = sensor;
    }}
{scalars}
    if (wmr_{name}_init(&state, &config) != WMR_OK) {{
        return 1;
    }}
    status = wmr_{name}_step(&state, &config, q, qdot, q_des, qdot_des, qddot_des, tau);
    sink = tau[0] + tau[1];
    return status < 0;
}}
"""
# The values a size image's configuration gets, by field (any controller's; the registry,
# as robot.py exports it, says which fields a controller has). Valid, not tuned: the image
# is measured, not flown.
IMAGE_FIELD_VALUES = {
    "k1": "WMR_LIT(4.0)", "k2": "WMR_LIT(4.0)", "q_pos": "WMR_LIT(1.0)",
    "q_vel": "WMR_LIT(1.0)", "h": "WMR_LIT(0.1)", "tau_max": "WMR_LIT(40.0)",
    "accel_estimator": "WMR_ACCEL_BACKWARD", "eps": "WMR_LIT(0.5)", "n": "4",
    "a": "WMR_LIT(0.9)", "alpha": "WMR_LIT(0.3)", "phi": "WMR_LIT(4.0)",
    "gamma": "WMR_LIT(2.0)", "kx": "WMR_LIT(1.0)", "ky": "WMR_LIT(8.0)",
    "ktheta": "WMR_LIT(4.0)", "kp": "WMR_LIT(2.0)", "ki": "WMR_LIT(2.0)",
}  # fields left out stay 0 (rate_window, hold_gain, held_gain, gain0)


def image_config_lines(name: str) -> tuple[str, str]:
    """(lines setting the vector fields inside the loop over i, lines setting the scalar
    fields) of ``name``'s size-image configuration."""
    fields = next(c["fields"] for c in generated_robot.CONTROLLERS if c["name"] == name)
    vectors, scalars = [], []
    for fname, kind, _, _ in fields:
        if fname in IMAGE_FIELD_VALUES:
            if kind == "vector":
                vectors.append(f"        config.{fname}[i] = {IMAGE_FIELD_VALUES[fname]};")
            else:
                scalars.append(f"    config.{fname} = {IMAGE_FIELD_VALUES[fname]};")
    return "\n".join(vectors), "\n".join(scalars)


FROZEN_MAIN_TEMPLATE = """\
#include "wmr_{name}.h"

/* A minimal firmware image with the configuration compiled in: initialised, stepped once. */
static wmr_{name}_state_t state;
volatile wmr_real_t sink;
volatile wmr_real_t sensor = WMR_LIT(0.1);

int main(void)
{{
    wmr_real_t q[5], qdot[5], q_des[5], qdot_des[5], qddot_des[5], tau[2];
    wmr_status_t status;
    int i;
    for (i = 0; i < 5; ++i) {{
        q[i] = sensor;
        qdot[i] = sensor;
        q_des[i] = sensor;
        qdot_des[i] = sensor;
        qddot_des[i] = sensor;
    }}
    if (wmr_{name}_init(&state, &wmr_{name}_frozen_config) != WMR_OK) {{
        return 1;
    }}
    status = wmr_{name}_step(&state, &wmr_{name}_frozen_config, q, qdot, q_des, qdot_des,
                            qddot_des, tau);
    sink = tau[0] + tau[1];
    return status < 0;
}}
"""


def frozen_define(name: str, prefix: str = "wmr") -> str:
    """The define of a build with ``name``'s configuration compiled in (``wmr freeze``)."""
    from runtime.freeze.header import frozen_macro

    return f"-D{frozen_macro(prefix, name)}"


def link_controller(objs: Objects, name: str, formulation: str = "PAPER") -> Path:
    """ELF of a tiny main calling wmr_<name>_init and _step (configured for the
    ``formulation``, or the controller's own where it has only one; in a frozen build, objs
    compiled with :func:`frozen_define`, with the compiled-in configuration), linked with
    newlib-nano; its link map beside it (``.map``)."""
    main = objs.dir / f"main_{name}.c"
    if frozen_define(name) in objs.defines:
        main.write_text(FROZEN_MAIN_TEMPLATE.format(name=name))
    else:
        vectors, scalars = image_config_lines(name)
        own = next(c["formulations"] for c in generated_robot.CONTROLLERS if c["name"] == name)
        if formulation.lower() not in own:
            formulation = own[0].upper()
        main.write_text(MAIN_TEMPLATE.format(name=name, vectors=vectors, scalars=scalars,
                                             formulation=f"WMR_FORMULATION_{formulation}"))
    elf = objs.dir / f"{name}.elf"
    flags = [*ARM_FLAGS, *SECTION_FLAGS, "-fstack-usage", f"-I{GENERATED_C}", *objs.defines]
    if objs.float32:
        flags.append("-DWMR_FLOAT32")
    run_tool(
        [
            ARM_GCC,
            *flags,
            str(main),
            *map(str, objs.objects),
            "--specs=nano.specs",
            "--specs=nosys.specs",
            "-Wl,--gc-sections",
            f"-Wl,-Map={elf.with_suffix('.map')}",
            "-lm",
            "-o",
            str(elf),
        ],
        cwd=objs.dir,
    )
    return elf
