"""Backends register through one protocol and share one intermediate form of a function.

The driver (``codegen.generate``) names no backend: a toy backend in its own package,
added to the registry by one entry, is rendered with the others; every registered backend
satisfies ``codegen.backend.Backend``; every backend receives the same ``RobotTarget``
whose functions were CSE'd once each before any backend ran. Uses the default robot
(Drishti, a few seconds), never the trailer.
"""

from __future__ import annotations

import inspect
import json
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

import codegen.backends as registry
from codegen import cse
from codegen.backend import Backend, FunctionIR, RobotTarget, function_ir
from codegen.backends.c.backend import config_for, default_config
from codegen.generate import generate_files, layout_for
from modeling.robot_file import load_robot_model

TOY = "toy_ops_backend"
TOY_SOURCE = '''
"""A backend that writes each function's operation count (from the shared IR) as JSON."""

import json


class OpsBackend:
    name = "toy-ops"
    folder = "toy"

    def __init__(self):
        self.seen = []

    def render(self, target):
        self.seen.append(target)
        counts = {
            m.name: {f.name: f.ops.comment() for f in m.functions} for m in target.modules
        }
        return {"ops.json": json.dumps(counts, indent=1, sort_keys=True) + "\\n"}


BACKEND = OpsBackend()
'''


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Generate the default robot with the toy backend registered, recording every CSE
    request and every backend call in order."""
    package = tmp_path_factory.mktemp("backend") / TOY
    package.mkdir()
    (package / "__init__.py").write_text(textwrap.dedent(TOY_SOURCE))
    events: list[tuple[str, Any]] = []
    model, robot = load_robot_model(None)
    real_cse = cse.cse_function

    def counting_cse(spec: Any, reciprocals: bool = False) -> cse.CseResult:
        events.append(("cse", spec))
        return real_cse(spec, reciprocals)

    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(package.parent))
        mp.setattr(registry, "REGISTERED", (*registry.REGISTERED, TOY))
        mp.setattr(cse, "_CACHE", {})  # CSE really runs, once per request
        mp.setattr(cse, "cse_function", counting_cse)
        backends = registry.registered()
        for backend in backends:
            original = backend.render

            def spy(target: RobotTarget, _b: Backend = backend, _f: Any = original) -> Any:
                events.append(("render", (_b.name, target)))
                return _f(target)

            mp.setattr(backend, "render", spy)
        out = generate_files(robot, model)
        toy = sys.modules.pop(TOY).BACKEND
    return {"out": out, "events": events, "toy": toy}


def test_registered_backends_satisfy_the_protocol() -> None:
    found = registry.registered()
    assert [b.name for b in found] == ["c", "python", "casadi"]
    for backend in found:
        assert isinstance(backend, Backend)
        assert backend.name and backend.folder and "/" not in backend.folder
        assert list(inspect.signature(backend.render).parameters) == ["target"]
    assert len({b.folder for b in found}) == len(found)


def test_registry_rejects_what_is_not_a_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry, "REGISTERED", ("codegen.spec",))
    with pytest.raises(TypeError, match=r"codegen\.spec\.BACKEND"):
        registry.registered()


def test_a_registered_backend_is_rendered_by_the_driver(run: dict[str, Any]) -> None:
    out = run["out"]
    counts = json.loads(out["toy/ops.json"])
    assert sorted(counts) == ["wmr_laws", "wmr_model", "wmr_plant"]
    # the toy's counts (from the IR) are the ones the C backend documents; a function with
    # a prepare-parameters API prints (and documents) the IR's split of it instead
    split = {f.name: f.prepared for f in run["toy"].seen[0].functions() if f.prepared}
    assert set(split) == {"forward_dynamics"}
    for module, functions in counts.items():
        header = out[f"c/{module}.h"].decode()
        for name, comment in functions.items():
            if name in split:
                comment = split[name].ops().comment()
            assert f"wmr_{name}(" in header and comment in header, (module, name)
    # the driver adds only its own files to what each backend returns, under its folder
    target = run["toy"].seen[0]
    expected = {"__init__.py", "MODEL.md", "toy/ops.json"}
    for backend in registry.registered():
        files = backend.render(target)
        expected |= {f"{backend.folder}/{name}" for name in files}
        for name, data in files.items():
            assert out[f"{backend.folder}/{name}"] == (
                data.encode() if isinstance(data, str) else data
            )
    assert set(out) == expected


def test_every_backend_gets_the_same_target_after_cse_ran_once_per_function(
    run: dict[str, Any],
) -> None:
    events = run["events"]
    renders = [data for kind, data in events if kind == "render"]
    assert [name for name, _ in renders] == ["c", "python", "casadi", "toy-ops"]
    targets = {id(target) for _, target in renders}
    assert len(targets) == 1
    target: RobotTarget = renders[0][1]
    assert run["toy"].seen == [target]
    # every CSE happened while the target was built, before any backend ran
    first_render = next(i for i, (kind, _) in enumerate(events) if kind == "render")
    requests = [spec for kind, spec in events if kind == "cse"]
    assert all(kind == "cse" for kind, _ in events[:first_render])
    assert len(requests) == first_render
    functions = list(target.functions())
    guarded = [f for f in functions if f.spec.guards]
    assert guarded, "Drishti's model functions have parameter guards"
    # once per function (its checked form), plus its outputs alone if it has guards
    assert len(requests) == len(functions) + len(guarded)
    assert all(isinstance(f, FunctionIR) for f in functions)
    for f in functions:
        assert f.cse.spec == f.spec.checked_spec()
        assert (f.plain is f.cse) == (not f.spec.guards)
        assert f.plain.spec == f.spec
        assert f.ops == cse.count_ops(f.cse)


def test_function_ir_is_the_cse_the_backends_used_to_run() -> None:
    model, _ = load_robot_model(None)
    from codegen.robot_functions import model_specs

    spec = next(s for s in model_specs(model) if s.guards)
    ir = function_ir(spec)
    assert ir.cse is cse.cse_function(spec.checked_spec(), reciprocals=True)
    assert ir.plain is cse.cse_function(spec)
    assert len(ir.cse.outputs) == len(spec.outputs) + 1  # the guard_ rows
    assert ir.name == spec.name


def test_default_c_config_is_the_default_robots() -> None:
    model, _ = load_robot_model(None)
    assert default_config() == config_for(layout_for(model))


def test_driver_and_main_name_no_backend() -> None:
    root = Path(__file__).resolve().parents[2] / "codegen"
    for name in ("generate.py", "__main__.py"):
        text = (root / name).read_text()
        for backend in ("backends.c", "backends.python", "backends.casadi", "CConfig"):
            assert backend not in text, (name, backend)
