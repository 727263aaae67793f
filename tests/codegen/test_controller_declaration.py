"""A controller with a new configuration field, declared in one place, generates C that
compiles and a Python mirror that has the field (issue 44: controllers declared, not
flagged).

The toy below is a PD law on the nominal model with one field no other controller has,
``kd_extra`` (an extra rate gain). It is declared here once, with the declaration API of
``modeling.controllers``, appended to a copy of the registry and generated for Drishti into
a temporary folder (no report): the C struct member, its check, ``<prefix>_field_t``'s
entry and the Python mirror's ``Config`` member all come from that one declaration. The C
is compiled with the strict flags of the generated code's build, run through cffi, and
compared with the Python mirror. About 25 s on one core (the derivation, then gcc -O0).
"""

from __future__ import annotations

import dataclasses
import importlib
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
import sympy as sp
from generated_code_support import C_FLAGS

from codegen.controller_api import FIELDS, detail_fields
from codegen.generate import generate_files
from modeling import controllers as ctl
from modeling.controllers import (
    REGISTRY,
    Check,
    ConfigField,
    ControllerSpec,
    Estimate,
    Kernel,
    KernelArg,
)
from modeling.controllers.declaration import law_args
from modeling.controllers.model import Formulation
from modeling.robot_file import load_robot_model
from modeling.robot_model import RobotModel
from runtime.bindings import cbuild

KD_EXTRA = ConfigField(
    "kd_extra", "real", Check.NONNEGATIVE_GAIN, "BAD_GAINS", "1/s",
    "toy PD: extra rate gain [1/s], [0, GAIN_MAX]", "zero", "0.5",
    about="the toy PD's extra rate gain")


def _pd_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    """u = M̂ (q̈_d + K1 e + K2 ė + kd_extra ė) + Ĥ(q, q̇): (18) with one more rate gain."""
    cm = ctl.control_model(formulation, model)
    ls = ctl.law_symbols(cm.size)
    kd = sp.Symbol("kd_extra", real=True)
    ua = ctl.nominal_acceleration(ls) + kd * ls.edot
    return Kernel(
        "toy PD: u = Mhat(q)(ua_hat + kd_extra edot) + Hhat(q, qdot).", ("(18)",),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         *law_args(ls, "e", "edot", "qddot_des", "k1", "k2"),
         KernelArg("kd", "config", (kd,), "kd_extra")),
        (KernelArg("u", "u", tuple(cm.mass * ua + cm.bias)),),
    )


# The toy, declared once: the field is in its own_fields and nowhere else.
PD = ControllerSpec("pd", "PD", "toy PD with an extra rate gain", "(18)", _pd_kernel,
                    Estimate.MODEL, own_fields=(KD_EXTRA,), formulations=("minimal",))
TOY_REGISTRY = (*REGISTRY, PD)
PACKAGE = "toy_declared_controller"


def test_template_switches_are_derived_not_stored() -> None:
    """A ControllerSpec stores what a law is (estimate, gain, error dynamics, states, own
    fields); the template switches are read from it, none is stored beside it."""
    stored = {f.name for f in dataclasses.fields(ControllerSpec)}
    switches = {"tde", "switching", "window", "bounds", "adaptive", "trig", "integrator"}
    assert not stored & switches
    assert (PD.tde, PD.switching, PD.window, PD.adaptive, PD.integrator) == (False,) * 5
    assert PD.fields[-1] is KD_EXTRA and PD.checks[-1] == "kd_extra"


def test_field_numbers_are_stable() -> None:
    """The registry's error-detail fields keep their numbers; a new field is appended."""
    assert detail_fields(TOY_REGISTRY) == (*FIELDS, ("KD_EXTRA", KD_EXTRA.detail_doc))
    clash = dataclasses.replace(KD_EXTRA, field_id=10)  # formulation's number
    with pytest.raises(ValueError, match="number"):
        detail_fields((*REGISTRY, dataclasses.replace(PD, own_fields=(clash,))))


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Drishti's code with the toy registered, under a package of its own."""
    model, robot = load_robot_model(None)
    root = tmp_path_factory.mktemp("toy") / PACKAGE
    for name, data in generate_files(robot, model, report=False,
                                     controllers=TOY_REGISTRY).items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    sys.path.insert(0, str(root.parent))
    yield root
    sys.path.remove(str(root.parent))
    for name in [m for m in sys.modules if m.split(".")[0] == PACKAGE]:
        del sys.modules[name]


@pytest.fixture(scope="module")
def mirror(generated: Path) -> ModuleType:
    return importlib.import_module(f"{PACKAGE}.python.controllers")


@pytest.fixture(scope="module")
def c_lib(generated: Path) -> cbuild.CLibrary:
    """Every generated .c compiled with the strict flags (as
    tests/generated/test_generated_c_build.py, at -O0), linked and bound."""
    src = generated / "c"
    out = generated / "build"
    out.mkdir()
    sources = sorted(p for p in src.glob("wmr_*.c"))
    objects = [out / f"{p.stem}.o" for p in sources]
    cbuild.run_compiler([cbuild.gcc_command([p], o, kind="object",
                                            flags=[*C_FLAGS, "-O0", "-fPIC"],
                                            include_dirs=[src])
                         for p, o in zip(sources, objects, strict=True)], jobs=2, silent=True)
    so = out / "libtoy.so"
    cbuild.run_compiler([cbuild.gcc_command(objects, so, kind="shared", libs=["-lm"])],
                        silent=True)
    return cbuild.load(so, cbuild.declarations(False, c_dir=src))


def _configs(mirror: ModuleType, c_lib: cbuild.CLibrary, **changes: Any) -> tuple[Any, Any]:
    """The mirror's Config of the toy and the same as ``wmr_pd_config_t``."""
    robot = importlib.import_module(f"{PACKAGE}.python.robot")
    config = dataclasses.replace(
        mirror.Config(nominal=dict(robot.PARAMS), formulation=mirror.FORMULATION_MINIMAL,
                      h=0.01, tau_max=200.0), **changes)
    c = c_lib.ffi.new("wmr_pd_config_t *")
    for name, ftype in c_lib.ffi.typeof("wmr_pd_config_t").fields:
        value = getattr(config, name)
        if name == "nominal":
            cbuild.fill_params(c.nominal, value, mirror.C_FIELD_NAMES)
        elif ftype.type.kind == "array":
            setattr(c, name, [float(x) for x in value])
        else:
            setattr(c, name, type(getattr(c, name))(value))
    return config, c


def test_python_mirror_has_the_field(mirror: ModuleType, generated: Path) -> None:
    assert "kd_extra" in {f.name for f in dataclasses.fields(mirror.Config)}
    assert mirror.Config(nominal={}).kd_extra == 0.5
    assert mirror.FIELDS["KD_EXTRA"] == len(FIELDS)
    assert ("kd_extra", "real") in mirror.PD.config_fields
    robot = importlib.import_module(f"{PACKAGE}.python.robot")
    pd = next(c for c in robot.CONTROLLERS if c["name"] == "pd")
    assert ("kd_extra", "real", "1/s", "zero") in pd["fields"]


def test_c_compiles_and_matches_the_mirror(mirror: ModuleType, c_lib: cbuild.CLibrary) -> None:
    """The struct has the field, its check names it, and a step is the mirror's."""
    ffi, lib = c_lib.ffi, c_lib.lib
    assert "kd_extra" in dict(ffi.typeof("wmr_pd_config_t").fields)
    config, c_config = _configs(mirror, c_lib, kd_extra=1.5)
    state = ffi.new("wmr_pd_state_t *")
    assert lib.wmr_pd_init(state, c_config) == mirror.STATUS["WMR_OK"]
    py = mirror.PD(config)
    rng = np.random.default_rng(44)
    inputs = [rng.uniform(-0.5, 0.5, 5) for _ in range(5)]
    tau = ffi.new("wmr_real_t[2]")
    status = lib.wmr_pd_step(state, c_config, *(ffi.new("wmr_real_t[5]", list(v))
                                                for v in inputs), tau)
    assert status == mirror.STATUS["WMR_OK"]
    assert np.allclose(list(tau), py.step(*inputs), rtol=1e-10, atol=1e-12)
    # a bad kd_extra: refused by both, with the field's own detail
    bad, c_bad = _configs(mirror, c_lib, kd_extra=-1.0)
    detail = ffi.new("wmr_error_detail_t *")
    status = lib.wmr_pd_check_config_detail(c_bad, detail)
    assert status == mirror.STATUS["WMR_ERR_BAD_GAINS"]
    assert detail.field == mirror.FIELDS["KD_EXTRA"] == lib.WMR_FIELD_KD_EXTRA
    with pytest.raises(mirror.ControllerError) as err:
        mirror.PD(bad)
    assert err.value.detail == (status, detail.field, -1)
