"""Shared by the tests of the checked-in generated code (``tests/generated/test_generated_*.py``,
``tests/codegen/test_codegen_cli.py``): constants, the strict-flag C builds (the session fixture
``c_builds`` of ``conftest.py`` calls :func:`build_generated_c`), the C and Python
controller configurations, a cffi controller wrapper and smooth input sequences.

The C is compiled from a snapshot of generated/c into pytest tmp directories, and bound,
through ``runtime.bindings.cbuild`` (the one cffi layer).
"""

from __future__ import annotations

import dataclasses
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from codegen.controller_api import CONTROLLERS, status_codes
from codegen.generate import layout_for
from modeling.robot_file import load_robot
from modeling.robots.drishti.model import PARAM_KEYS, PARAMETERS, robot_model
from runtime.bindings import cbuild
from runtime.bindings.generated import controllers as pyctl

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
FLOOR = 1e-6
RTOL_CONTROLLER = 1e-10  # C step vs Python step
C_FLAGS = [
    "-std=c99",
    "-Wall",
    "-Wextra",
    "-Wpedantic",
    "-Wshadow",
    "-Wdouble-promotion", "-Wfloat-equal",
    "-Wconversion",
    "-Werror",
]
STATUS_CODES = status_codes(layout_for(robot_model()))
STATUS = {s.name: s.value for s in STATUS_CODES}
DRISHTI = load_robot().lumped
PARAM_SYMBOLS = tuple(p.symbol for p in PARAMETERS)
C_FIELD = robot_model().c_field_names()  # key -> C member, where they differ
INFO = {c.name: c for c in CONTROLLERS}
PY_CLASSES = {c.name: getattr(pyctl, c.name.upper()) for c in CONTROLLERS}
FORMULATIONS = {"paper": 0, "minimal": 1}


@dataclass
class CBuild:
    ffi: Any
    lib: Any
    float32: bool
    objects: dict[str, Path]
    example: Path


def _gcc() -> str:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not available")
    return gcc


def _headers(src: Path) -> tuple[str, ...]:
    """The generated headers for cffi (types first; not the robot's constants header)."""
    others = ("wmr_types.h", "wmr_robot.h")
    return ("wmr_types.h", *sorted(p.name for p in src.glob("wmr_*.h") if p.name not in others))


def build_generated_c(tmp_path_factory: pytest.TempPathFactory) -> dict[str, CBuild]:
    """Every generated .c compiled with the strict flags in both precisions (objects, a
    shared library of the wmr_*.c for cffi, and the example executable), through
    ``runtime.bindings.cbuild``; every compiler run must succeed silently."""
    _gcc()
    root = tmp_path_factory.mktemp("generated_c")
    src = root / "src"
    shutil.copytree(GENERATED / "c", src)  # a snapshot: concurrent regeneration is harmless
    sources = sorted(src.glob("*.c"))
    assert {p.name for p in sources} >= {"example_main.c", "wmr_model.c", "wmr_laws.c"}
    builds: dict[str, CBuild] = {}
    cmds: list[list[str]] = []
    objects: dict[str, dict[str, Path]] = {}
    for precision in ("double", "float"):
        out = root / precision
        out.mkdir()
        defines = ["-DWMR_FLOAT32"] if precision == "float" else []
        objects[precision] = {p.name: out / f"{p.stem}.o" for p in sources}
        cmds += [
            cbuild.gcc_command([p], o, kind="object", flags=[*C_FLAGS, "-O2", "-fPIC", *defines],
                               include_dirs=[src])
            for p, o in zip(sources, objects[precision].values(), strict=True)
        ]
    cbuild.run_compiler(cmds, jobs=2, silent=True)  # 2 cores
    links = []
    for precision in ("double", "float"):
        objs = objects[precision]
        lib_objs = [o for n, o in objs.items() if n != "example_main.c"]
        so = root / precision / "libwmr.so"
        exe = root / precision / "example_main"
        links.append(cbuild.gcc_command(lib_objs, so, kind="shared", libs=["-lm"]))
        links.append(cbuild.gcc_command([objs["example_main.c"], *lib_objs], exe,
                                        kind="executable", libs=["-lm"]))
    cbuild.run_compiler(links, jobs=2, silent=True)
    for precision in ("double", "float"):
        float32 = precision == "float"
        lib = cbuild.load(root / precision / "libwmr.so",
                          cbuild.declarations(float32, _headers(src), c_dir=src),
                          float32=float32)
        builds[precision] = CBuild(
            lib.ffi, lib.lib, float32, objects[precision], root / precision / "example_main"
        )
    return builds


def _c_params(ffi: Any, values: Sequence[float] | dict[str, float]) -> Any:
    obj = ffi.new("wmr_params_t *")
    items = values.items() if isinstance(values, dict) else zip(PARAM_KEYS, values, strict=True)
    for key, value in items:
        setattr(obj, C_FIELD.get(key, key), float(value))
    return obj


def _config(name: str, formulation: int, **changes: Any) -> Any:
    config = pyctl.Config(
        nominal=dict(DRISHTI),
        formulation=formulation,
        k1=[4.0, 5.0, 6.0, 7.0, 8.0],
        k2=[3.0, 3.5, 4.0, 4.5, 5.0],
        q_pos=1.5,
        q_vel=0.8,
        h=0.01,
        tau_max=200.0,
        eps=0.05,
        n=4,
        a=0.8,
        alpha=0.3,
        phi=2.0,
        gamma=2.0,
        gain0=0.5 if name == "asmc" else 0.0,
    )
    return dataclasses.replace(config, **changes)


def _c_config(build: CBuild, name: str, config: Any) -> Any:
    """``wmr_<name>_config_t`` with every field taken from the Python Config."""
    ffi = build.ffi
    ctype = f"wmr_{name}_config_t"
    obj = ffi.new(f"{ctype} *")
    for field, ftype in ffi.typeof(ctype).fields:
        value = getattr(config, field)
        if field == "nominal":
            obj.nominal = _c_params(ffi, dict(value))[0]
        elif ftype.type.kind == "array":
            setattr(obj, field, [float(x) for x in value])
        elif ftype.type.cname in ("int", "long"):
            setattr(obj, field, int(value))
        else:
            setattr(obj, field, float(value))
    return obj


def _c_value(ffi: Any, value: Any) -> Any:
    if not isinstance(value, ffi.CData):
        return value
    t = ffi.typeof(value)
    if t.kind == "array":
        return np.array([_c_value(ffi, v) for v in value])
    if t.kind == "struct":
        return {f: _c_value(ffi, getattr(value, f)) for f, _ in t.fields}
    raise TypeError(t)


class CController:
    """``wmr_<name>_init`` / ``_step`` through cffi with a caller-owned state."""

    def __init__(self, build: CBuild, name: str, config: Any) -> None:
        self.build, self.name = build, name
        self.config = _c_config(build, name, config)
        self.state = build.ffi.new(f"wmr_{name}_state_t *")
        status = self.init()
        assert status == STATUS["WMR_OK"], status

    def init(self, config: Any = None) -> int:
        init = getattr(self.build.lib, f"wmr_{self.name}_init")
        return int(init(self.state, self.config if config is None else config))

    def step(self, *inputs: np.ndarray, config: Any = None, tau: Any = None) -> tuple[int, Any]:
        ffi = self.build.ffi
        tau = ffi.new("wmr_real_t[2]") if tau is None else tau
        arrays = [ffi.new("wmr_real_t[5]", [float(x) for x in v]) for v in inputs]
        step = getattr(self.build.lib, f"wmr_{self.name}_step")
        status = step(self.state, self.config if config is None else config, *arrays, tau)
        return int(status), tau

    def fields(self) -> dict[str, Any]:
        return _c_value(self.build.ffi, self.state[0])

    def raw(self) -> bytes:
        return bytes(self.build.ffi.buffer(self.state))


def _smooth_sequence(seed: int, steps: int, h: float) -> list[tuple[np.ndarray, ...]]:
    """(q, qdot, q_des, qdot_des, qddot_des) per step: sums of sinusoids on a drift, the
    reference a smooth offset of the measured motion (a closed loop that tracks)."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) * h

    def signal(amplitude: np.ndarray, drift: np.ndarray) -> tuple[np.ndarray, ...]:
        a = rng.uniform(0.3, 1.0, (5, 3)) * amplitude[:, None]
        w = 2 * np.pi * rng.uniform(0.1, 0.6, (5, 3))
        ph = rng.uniform(0.0, 2 * np.pi, (5, 3))
        arg = w[None] * t[:, None, None] + ph[None]
        q = drift[None] * t[:, None] + (a[None] * np.sin(arg)).sum(-1)
        qd = drift[None] + (a[None] * w[None] * np.cos(arg)).sum(-1)
        qdd = -(a[None] * w[None] ** 2 * np.sin(arg)).sum(-1)
        return q, qd, qdd

    drift = np.array([0.3, 0.1, 0.05, 2.0, 1.5])
    q, qd, _ = signal(np.array([0.5, 0.5, 0.3, 0.5, 0.5]), drift)
    e, ed, edd = signal(np.array([0.05, 0.05, 0.05, 0.1, 0.1]), np.zeros(5))
    return [(q[k], qd[k], q[k] + e[k], qd[k] + ed[k], edd[k]) for k in range(steps)]


def _close(a: Any, b: Any, rtol: float) -> bool:
    a, b = np.atleast_1d(np.asarray(a, dtype=np.float64)), np.atleast_1d(np.asarray(b, dtype=float))
    if a.shape != b.shape:
        return False
    return bool(np.linalg.norm(a - b) <= rtol * max(float(np.linalg.norm(b)), FLOOR))


CONTROLLER_CASES = [(c, f) for c in INFO for f in FORMULATIONS if f in INFO[c].formulations]
CONTROLLER_IDS = [f"{c}-{f}" for c, f in CONTROLLER_CASES]
