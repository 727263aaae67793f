"""``python -m codegen.backends.c.certify --only``: re-certifies the named functions and
steps (and the steps reading them), keeps every other stored entry byte for byte, and
refuses an unknown name, or a stored result it needs that is stale, with one line and
nothing written. And a function certified over its producer's image (compose.py)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from codegen.backend import RobotTarget
from codegen.backends.c.backend import config_for
from codegen.backends.c.certify import __main__ as cli
from codegen.backends.c.certify import steps as steps_module
from codegen.backends.c.certify.bound import certify
from codegen.backends.c.certify.boxes import DERIVED, ENVELOPE, box_of, derived_key
from codegen.backends.c.certify.compose import ComposedExact, composed
from codegen.backends.c.certify.only import Refused, plan_only, step_inputs
from codegen.backends.c.certify.robot import programs, robot_angles, robot_params
from codegen.backends.c.certify.search import Exact, node_values
from codegen.backends.c.certify.steps import step_certificates, steps_of
from codegen.backends.c.lowering import function_context
from codegen.certify.header import body_hash
from codegen.certify.stored import RESULTS_DIR
from codegen.generate import robot_target
from modeling.robot_file import load_robot_model, model_of, robot_source
from modeling.robot_io import shipped_robot_file


@pytest.fixture(scope="module")
def drishti() -> RobotTarget:
    model, robot = load_robot_model(None)
    return robot_target(model, robot)


@pytest.fixture
def results(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of the committed results the command reads and writes."""
    for path in RESULTS_DIR.glob("*.json"):
        shutil.copy(path, tmp_path / path.name)
    monkeypatch.setattr(cli, "RESULTS_DIR", tmp_path)
    monkeypatch.setattr(cli, "DOC", tmp_path / "FLOAT32.md")
    return tmp_path


def _entries(data: dict[str, Any]) -> dict[str, str]:
    """Each function's and step's entry as the command writes it."""
    out = {f"function {r['function']}": json.dumps(r, indent=1, sort_keys=True)
           for r in data["functions"]}
    out.update({f"step {s['controller']}/{s['formulation']}": json.dumps(s, indent=1,
                                                                         sort_keys=True)
                for s in data["steps"]})
    return out


def test_only_rewrites_the_named_entry_and_keeps_the_others(results: Path) -> None:
    before = {p.name: p.read_text() for p in results.glob("*.json")}
    assert cli.main(["--robot", "drishti", "--only", "mass_matrix", "--seconds", "0.2",
                     "--search", "3"]) == 0
    old = _entries(json.loads(before["drishti.json"]))
    data = json.loads((results / "drishti.json").read_text())
    new = _entries(data)
    assert set(new) == set(old)
    changed = {k for k in old if new[k] != old[k]}
    assert changed == {"function mass_matrix"}  # its search ran 3 points, not the stored run's
    assert [r["function"] for r in data["functions"]] == [
        r["function"] for r in json.loads(before["drishti.json"])["functions"]]
    assert {k: v for k, v in data.items() if k not in ("functions", "steps")} == {
        k: v for k, v in json.loads(before["drishti.json"]).items()
        if k not in ("functions", "steps")}
    assert (results / "trailer.json").read_text() == before["trailer.json"]
    assert "mass_matrix" in (results / "FLOAT32.md").read_text()


def test_an_unknown_name_is_refused_with_one_line(
        results: Path, capsys: pytest.CaptureFixture[str]) -> None:
    before = {p.name: p.read_text() for p in results.glob("*.json")}
    assert cli.main(["--robot", "drishti", "--only", "mass_matrix,mass_matirx"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mass_matirx" in err and "mass_matrix," not in err
    assert {p.name: p.read_text() for p in results.glob("*.json")} == before
    assert not (results / "FLOAT32.md").exists()


def test_steps_reading_a_named_function_are_recertified(drishti: RobotTarget) -> None:
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    plan = plan_only("drishti", drishti, stored, ["tdroc_weighted_gain"])
    steps = list(steps_of(drishti, {ir.name for ir, _ in programs(drishti)}))
    windowed = {s.key for s in steps if s.gain == "tdroc_weighted_gain"}
    assert windowed and plan.steps == windowed and plan.functions == {"tdroc_weighted_gain"}
    # a step named alone: the functions it combines are read from the stored results
    plan = plan_only("drishti", drishti, stored, ["roc/minimal"])
    assert plan.steps == {"roc/minimal"} and not plan.functions
    assert {"minimal_roc_law", "lyapunov_p"} <= set(plan.stored)
    assert {"p12", "p22"} <= set(plan.derived)


def test_a_stale_stored_result_it_needs_is_refused(drishti: RobotTarget) -> None:
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    for row in stored["functions"]:
        if row["function"] == "lyapunov_p":
            row["hash"] = "0" * 16
    plan_only("drishti", drishti, stored, ["mass_matrix"])  # reads nothing stored
    with pytest.raises(Refused, match=r"lyapunov_p.*stale"):
        plan_only("drishti", drishti, stored, ["minimal_roc_law"])  # its box reads P


@pytest.fixture(scope="module")
def trailer() -> RobotTarget:
    model, robot = model_of(robot_source(shipped_robot_file("trailer")))
    return robot_target(model, robot)


def test_composed_program_is_the_function_of_q_its_step_computes(trailer: RobotTarget) -> None:
    """minimal_minv_norm_mhat over M-hat as minimal_mhat computes it (compose.py): its
    program in double and its exact reference agree with minimal_minv_norm, the same
    quantity generated as one function of q (a wrong wiring of M-hat's entries fails)."""
    own = {ir.name: (ir, prog) for ir, prog in programs(trailer)}
    (first, first_prog), (second, second_prog) = own["minimal_mhat"], own[
        "minimal_minv_norm_mhat"]
    wiring = {a: DERIVED[derived_key(a)][1][0] for a in second_prog.input_names.values()
              if derived_key(a)}
    assert wiring and set(wiring.values()) <= {lv for lv, _ in first_prog.outputs}
    prog = composed(first_prog, second_prog, wiring)
    assert prog.producer == "minimal_mhat" and not any(
        derived_key(a) for a in prog.input_names.values())
    ref_ir, ref_prog = own["minimal_minv_norm"]
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    assert set(symbols) == set(ref_prog.inputs)
    angles, params = robot_angles(trailer), robot_params(trailer, ENVELOPE)
    box = box_of(ref_prog, angles, params, {}, ENVELOPE)
    rng = np.random.default_rng(3)
    pts = np.array([[rng.uniform(*box[s]) for s in symbols] for _ in range(6)])
    ours = node_values(prog, {s: pts[:, k] for k, s in enumerate(symbols)}, np.float64)
    theirs = node_values(ref_prog, {s: pts[:, k] for k, s in enumerate(symbols)}, np.float64)
    for (_, n), (_, m) in zip(prog.outputs, ref_prog.outputs, strict=True):
        assert np.allclose(ours[n], theirs[m], rtol=1e-9, atol=0)
    exact = ComposedExact(first, second, first_prog, second_prog, wiring, symbols)
    reference = Exact(ref_ir, symbols)
    for p in pts:
        got, want = exact(list(p)), reference(list(p))
        assert all(abs(g - w) <= 1e-25 * abs(w) for g, w in zip(got, want, strict=True))


def test_steps_take_the_estimate_over_its_enclosure_and_state_the_gain_conditions(
        drishti: RobotTarget, monkeypatch: pytest.MonkeyPatch) -> None:
    """A TDC step's law is certified with H1hat over the estimator's certified enclosure
    (wider than the law's declared box), so it needs no condition; a TDROC step names the
    gain's conditions its bound holds under."""
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    plan = plan_only("drishti", drishti, stored, ["tdc/minimal", "tdroc/minimal"])
    certs: dict[str, Any] = {}
    step_inputs(drishti, plan, certs)
    seen: dict[str, dict[Any, tuple[float, float]]] = {}

    def spy(prog: Any, box: Any, errs: Any, seconds: float) -> Any:
        seen[prog.function] = dict(box)
        return certify(prog, box, errs, seconds=0.1, max_boxes=1)

    monkeypatch.setattr(steps_module, "certify", spy)
    rows = {s.controller: s for s in step_certificates(drishti, certs,
                                                       only={"tdc/minimal", "tdroc/minimal"})}
    prog, declared, _ = certs["minimal_tdc_law"]
    est = certs["minimal_tde"][2]
    h1 = [s for s, a in prog.input_names.items() if a.startswith("H1hat")]
    assert h1 and all(seen["minimal_tdc_law"][s][1] >= max(r[1] for r in est.ranges) >
                      declared[s][1] for s in h1)
    assert rows["tdc"].reason == "" or "k-hat" not in rows["tdc"].reason
    assert not rows["tdroc"].proved and rows["tdroc"].reason.startswith("if k-hat stays in")


def test_committed_compositions_are_current(trailer: RobotTarget) -> None:
    """A row certified over its producer's image (compose.py) is stale when the producer's
    printing changes too, which the row's own hash does not see: its ``composed`` hash must
    match the producer printed now (re-certify with ``--only <producer>``)."""
    config = config_for(trailer.layout)
    irs = {ir.name: ir for ir in trailer.functions()}
    rows = [r for r in json.loads((RESULTS_DIR / "trailer.json").read_text())["functions"]
            if r.get("composed")]
    assert [r["function"] for r in rows] == ["minimal_minv_norm_mhat"]
    for row in rows:
        producer = irs[row["composed"]["function"]]
        assert row["composed"]["hash"] == body_hash(
            function_context(producer, config, "")["body"]), row["function"]


def test_stale_names_the_functions_whose_printing_changed(drishti: RobotTarget) -> None:
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    assert not plan_only("drishti", drishti, stored, ["stale"])  # the committed are current
    for row in stored["functions"]:
        if row["function"] == "kinematics":
            row["hash"] = "0" * 16
    plan = plan_only("drishti", drishti, stored, ["stale"])
    assert plan.functions == {"kinematics"} and "stale" in plan.known


def test_stale_with_nothing_stale_writes_nothing(
        results: Path, capsys: pytest.CaptureFixture[str]) -> None:
    before = {p.name: p.read_text() for p in results.glob("*.json")}
    assert cli.main(["--robot", "drishti", "--only", "stale"]) == 0
    assert "nothing to re-certify" in capsys.readouterr().out
    assert {p.name: p.read_text() for p in results.glob("*.json")} == before
    assert not (results / "FLOAT32.md").exists()


def test_a_producer_brings_the_functions_whose_box_it_makes(drishti: RobotTarget) -> None:
    """Re-certifying lyapunov_p changes P's enclosure, the box of every law reading it."""
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    plan = plan_only("drishti", drishti, stored, ["lyapunov_p"])
    readers = {ir.name for ir, prog in programs(drishti)
               if any(a.startswith("p12") for a in prog.input_names.values())}
    assert readers and readers | {"lyapunov_p"} == plan.functions


def test_an_adapted_gain_step_states_that_its_gain_must_stay_in_the_box(
        drishti: RobotTarget, monkeypatch: pytest.MonkeyPatch) -> None:
    """ASMC's law reads the gain the state carries, which the step caps at GAIN_MAX only:
    its bound holds if that gain stays in the law's declared box, and the row says so (it
    is not 'proved'); PI's law reads no gain and needs no such condition."""
    keys = ["asmc/minimal", "pi/minimal"]
    stored = json.loads((RESULTS_DIR / "drishti.json").read_text())
    plan = plan_only("drishti", drishti, stored, keys)
    certs: dict[str, Any] = {}
    step_inputs(drishti, plan, certs)
    monkeypatch.setattr(steps_module, "certify", lambda prog, box, errs, seconds: certify(
        prog, box, errs, seconds=0.1, max_boxes=1))
    rows = {s.controller: s for s in step_certificates(drishti, certs, only=set(keys))}
    assert not rows["asmc"].proved
    assert rows["asmc"].reason.startswith("if the adapted gain the state carries stays in")
    assert "adapted gain" not in rows["pi"].reason
    committed = {s["controller"]: s for s in stored["steps"] if s["formulation"] == "minimal"}
    assert not committed["asmc"]["proved"] and "adapted gain" in committed["asmc"]["reason"]
