"""Robot descriptions: Drishti described as bodies and wheels is the paper's model, the
structural checks (redundant rows, degrees of freedom, existence of S), and bad files.

Drishti from its lumped parameters (``modeling.robots.drishti.description``) is compared
with ``modeling.robots.drishti.model``: the kinetic energy symbolically (exact equality
after renaming the coordinates), A, Sᵀ M S and Sᵀ(M Ṡ η + H) symbolically, and S, Ṡη, the
minimal and the reduced (14) forms and the forward dynamics numerically at N_STATES random
consistent states for Drishti's parameters and perturbed ones, to RTOL = 1e-12 relative to
each quantity's largest value over the states (see ``compare_with_wmr``). The
``tests/robots/drishti_bodies.toml`` (the same robot written as numbers) is compared likewise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp
from description_numeric import numeric_description, parameter_vector, trailer

from modeling.description import (
    BodySpec,
    DescriptionError,
    JointSpec,
    RobotDescription,
    WheelSpec,
    coordinates,
    description_kinetic_energy,
    description_system,
    load_description,
    packaged_description,
    parse_description,
    symbolize,
)
from modeling.description.canonical import trig_reduce
from modeling.description.elimination import block_triangular_inverse
from modeling.lagrange import default_simplify
from modeling.robot_file import RobotFileError, load_robot, shipped_robot_file
from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.description import drishti_from_lumped, wmr_renaming

ROBOTS = Path(__file__).resolve().parents[1] / "robots"

RTOL = 1e-12
N_STATES = 100
SEED = 4142


def zero(m: sp.Matrix) -> bool:
    return all(sp.simplify(e) == 0 for e in m)


# ---------------------------------------------------------------------------------------
# Drishti from the lumped parameters ≡ modeling.robots.drishti.model
# ---------------------------------------------------------------------------------------
def test_lumped_drishti_kinetic_energy_is_wmrs_exactly() -> None:
    desc = drishti_from_lumped()
    t = description_kinetic_energy(desc).xreplace(wmr_renaming(coordinates(symbolize(desc))))
    assert sp.expand(t - wmr.lumped_kinetic_energy()) == 0
    # not vacuous: a different K gives a different energy
    wrong = drishti_from_lumped(K=2 * wmr.K)
    t_wrong = description_kinetic_energy(wrong).xreplace(wmr_renaming(coordinates(wrong)))
    assert sp.expand(t_wrong - wmr.lumped_kinetic_energy()) != 0


def test_lumped_drishti_constraints_match_wmr() -> None:
    """Same row space as wmr's A ((6)–(8)): each annihilates the other's null space; the
    redundant no-side-slip row of the second wheel is dropped, and with the rows in the
    description's fixed order A is wmr's A exactly (the paper's signs)."""
    s = description_system(drishti_from_lumped())
    w = wmr.wmr_system()
    ren = wmr_renaming(s)
    a = s.constraint_matrix.xreplace(ren)
    assert a.rank(simplify=True) == 3
    assert zero(w.constraint_matrix * s.null_space.xreplace(ren))
    assert zero(a * w.null_space)
    assert s.dropped_constraints == ("no side slip of wheel 'left'",)
    assert zero(a - wmr.constraint_matrix())
    assert s.independent == w.independent == (3, 4)
    assert s.input_matrix == w.input_matrix


def test_lumped_drishti_minimal_form_is_wmrs_symbolically() -> None:
    s = description_system(drishti_from_lumped())
    w = wmr.wmr_system()
    ren = wmr_renaming(s)
    for mine, theirs in ((s.minimal_mass_matrix, w.minimal_mass_matrix),
                         (s.minimal_bias, w.minimal_bias),
                         (s.minimal_input_matrix, w.minimal_input_matrix)):
        diff = (mine.xreplace(ren) - theirs).applyfunc(default_simplify)
        assert diff == sp.zeros(*theirs.shape)


def wmr_params(rng: np.random.Generator | None) -> np.ndarray:
    """(m, I, K, K_lat, I_w, r, b, d): Drishti's, or each scaled by U(0.7, 1.3) with
    I > K²/m kept."""
    lumped = load_robot().lumped
    base = np.array([lumped[k] for k in ("m", "I", "K")] + [0.0]
                    + [lumped[k] for k in ("Iw", "r", "b", "d")])
    while rng is not None:
        p = base * rng.uniform(0.7, 1.3, base.size)
        p[3] = 0.0
        if p[1] > p[2] ** 2 / p[0]:
            return p
    return base


PARAM_SETS = [("drishti", None), ("perturbed0", 1), ("perturbed1", 2)]


def compare_with_wmr(
    paper_model: Any, model: Any, p_desc: np.ndarray, p_wmr: np.ndarray, seed: int
) -> dict[str, float]:
    """Worst ‖x − x_wmr‖ over the states divided by the largest ‖x_wmr‖ over the states.

    Relative to the sample's scale rather than pointwise: Ṡη and the bias are sums of
    expanded velocity products that cancel when the two wheel rates nearly agree
    (straight-line motion), and there a pointwise relative error measures the rounding of
    two different expansions (the file's 207/1000 against b/2), not the model.
    """
    err: dict[str, float] = {}
    scale: dict[str, float] = {}

    def note(key: str, mine: np.ndarray, theirs: np.ndarray) -> None:
        err[key] = max(err.get(key, 0.0), float(np.linalg.norm(np.ravel(mine - theirs))))
        scale[key] = max(scale.get(key, 0.0), float(np.linalg.norm(theirs)))

    for q, eta, _, tau in paper_model_states(paper_model, p_wmr, seed):
        qd = paper_model.qdot_on_manifold(q, eta, p_wmr)
        note("S", model.S(q, p=p_desc), paper_model.S(q, p=p_wmr))
        note("Sdot_eta", model.Sdot_eta(q, qd, p=p_desc), paper_model.Sdot_eta(q, qd, p=p_wmr))
        note("M_min", model.M_min(q, p=p_desc), paper_model.M_min(q, p=p_wmr))
        note("H_min", model.H_min(q, qd, p=p_desc), paper_model.H_min(q, qd, p=p_wmr))
        note("M_red", model.M_red(q, qd, p=p_desc), paper_model.M_red(q, qd, p=p_wmr))
        note("H_red", model.H_red(q, qd, p=p_desc), paper_model.H_red(q, qd, p=p_wmr))
        note("eta_dot", model.eta_dot(q, qd, tau=tau, p=p_desc),
             paper_model.eta_dot(q, qd, tau=tau, p=p_wmr))
        note("qdd_red", model.qdd_red(q, qd, tau=tau, p=p_desc),
             paper_model.qdd_red(q, qd, tau=tau, p=p_wmr))
    assert min(scale.values()) > 0, scale
    return {key: err[key] / scale[key] for key in err}


def paper_model_states(
    paper_model: Any, p: np.ndarray, seed: int
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(N_STATES):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi), rng.uniform(-50, 50, 2)]
        eta = rng.uniform(-15, 15, 2)
        out.append((q, eta, paper_model.qdot_on_manifold(q, eta, p), rng.uniform(-10, 10, 2)))
    return out


@pytest.mark.parametrize("seed", [s for _, s in PARAM_SETS], ids=[n for n, _ in PARAM_SETS])
def test_lumped_drishti_reduced_forms_match_wmr_numerically(
    paper_model: Any, seed: int | None
) -> None:
    model = numeric_description(drishti_from_lumped())
    p_wmr = wmr_params(None if seed is None else np.random.default_rng(seed))
    by_symbol = dict(zip(wmr.PLANT_SYMBOLS, p_wmr, strict=True))
    p_desc = np.array([by_symbol[s] for s in model.system.parameters])
    worst = compare_with_wmr(paper_model, model, p_desc, p_wmr, seed=SEED + (seed or 0))
    assert max(worst.values()) < RTOL, worst


def test_drishti_bodies_file_is_drishti(paper_model: Any, drishti: np.ndarray) -> None:
    """The packaged file holds drishti_from_lumped at the paper's numbers (to the float
    rounding of K/m and I − K²/m), and its model is the paper's (symbols per field)."""
    from_file = load_description(ROBOTS / "drishti_bodies.toml")
    m, i, k, _, iw, r, b, d = drishti
    built = drishti_from_lumped(m, i, k, iw, r, b, d)
    assert replace(from_file, name="drishti") == built
    model = numeric_description(from_file)
    p_desc = parameter_vector(model.system, from_file)
    worst = compare_with_wmr(paper_model, model, p_desc, drishti, seed=SEED)
    assert max(worst.values()) < RTOL, worst


def test_drishti_comparison_has_teeth(paper_model: Any, drishti: np.ndarray) -> None:
    """A 1 % error in the platform's centre of mass is seen by the comparison."""
    desc = load_description(ROBOTS / "drishti_bodies.toml")
    body = desc.bodies[0]
    wrong = replace(desc, bodies=(replace(body, com=(1.01 * body.com[0], body.com[1])),))
    model = numeric_description(desc)
    worst = compare_with_wmr(paper_model, model, parameter_vector(model.system, wrong),
                             drishti, seed=SEED)
    assert worst["M_min"] > 1e-6 or worst["H_min"] > 1e-6


# ---------------------------------------------------------------------------------------
# Structure: redundant rows, coordinates, symbols, the elimination helpers
# ---------------------------------------------------------------------------------------
def test_trailer_structure() -> None:
    s = description_system(trailer())
    assert s.coordinate_names == ("x_tractor", "y_tractor", "theta_tractor", "theta_cart",
                                  "theta_right", "theta_left", "theta_cart_right",
                                  "theta_cart_left")
    assert s.independent == (4, 5)
    assert s.dropped_constraints == ("no side slip of wheel 'left'",
                                     "no side slip of wheel 'cart_left'")
    assert s.constraint_matrix.shape == (6, 8)
    assert [str(t) for t in s.inputs] == ["tau_right", "tau_left"]
    # geometry exact, inertial fields symbolic with their values
    sym = symbolize(trailer())
    assert sym.wheels[0].position == (0, sp.Rational(-207, 1000))
    assert sym.values[sp.Symbol("mass_cart", real=True)] == 15.0


def test_driven_wheels_come_first_in_file_order() -> None:
    desc = trailer()
    wheels = (replace(desc.wheels[2], driven=True), replace(desc.wheels[0], driven=False),
              desc.wheels[1], desc.wheels[3])
    names = coordinates(replace(desc, wheels=wheels)).names
    assert names[4:] == ("theta_cart_right", "theta_left", "theta_right", "theta_cart_left")


def test_trig_reduce_is_the_canonical_form_of_lagrange() -> None:
    s = description_system(trailer())
    exprs = [*s.mass_matrix, *s.bias, *s.constraint_rate_term]
    assert all(trig_reduce(e) == default_simplify(e) for e in exprs)
    th = sp.Symbol("th")
    assert trig_reduce(sp.sin(th) ** 3 + sp.sin(th) * sp.cos(th) ** 2) == sp.sin(th)


def test_block_triangular_inverse() -> None:
    s = description_system(trailer())
    a_d = s.constraint_matrix.extract(list(range(6)), list(s.dependent))
    inv = s.dependent_block_inverse
    assert (inv * a_d).applyfunc(trig_reduce) == sp.eye(6)
    with pytest.raises(ZeroDivisionError):
        block_triangular_inverse(sp.Matrix([[1, 0, 0], [0, 0, 1], [2, 0, 0]]))


# ---------------------------------------------------------------------------------------
# Robots that have no minimal form with the driven wheels as independent speeds
# ---------------------------------------------------------------------------------------
def wheel(name: str, x: float, y: float, driven: bool = True, body: str = "base") -> WheelSpec:
    return WheelSpec(name, body, (x, y), 0.1, 0.01, 0.001, 1.0, driven)


BASE = BodySpec("base", 10.0, 1.0, (0.0, 0.0))
STRUCTURE_ERRORS: list[tuple[str, RobotDescription, tuple[str, ...]]] = [
    ("one driven wheel", RobotDescription("uni", (BASE,), (), (
        wheel("r", 0, -0.2), wheel("l", 0, 0.2, driven=False))),
     ("2 degree(s) of freedom", "1 driven wheel")),
    ("three driven wheels on one axle", RobotDescription("tri", (BASE,), (), (
        wheel("r", 0, -0.2), wheel("m", 0, 0.0), wheel("l", 0, 0.2))),
     ("2 degree(s) of freedom", "3 driven wheel")),
    ("skid steer: two axles", RobotDescription("skid", (BASE,), (), (
        wheel("fr", 0.2, -0.2), wheel("fl", 0.2, 0.2), wheel("rr", -0.2, -0.2),
        wheel("rl", -0.2, 0.2))),
     ("1 degree(s) of freedom", "4 driven wheel")),
    ("no driven wheel", RobotDescription("cart", (BASE,), (), (
        wheel("r", 0, -0.2, driven=False), wheel("l", 0, 0.2, driven=False))),
     ("2 degree(s) of freedom", "0 driven wheel")),
    ("trailer axle under the hitch", replace(trailer(), wheels=tuple(
        replace(w, position=(0.0, w.position[1])) if w.body == "cart" else w
        for w in trailer().wheels)),
     ("S(q) does not exist", "theta_cart")),
]


@pytest.mark.parametrize(("desc", "words"), [c[1:] for c in STRUCTURE_ERRORS],
                         ids=[c[0] for c in STRUCTURE_ERRORS])
def test_structure_errors_name_the_problem(desc: RobotDescription, words: tuple[str, ...]) -> None:
    with pytest.raises(DescriptionError) as info:
        description_system(desc, numeric=True)
    for word in words:
        assert word in str(info.value), (word, str(info.value))
    assert isinstance(info.value, ValueError)


def test_dependent_at_values_only_is_refused() -> None:
    """Symbolic geometry whose values make two no-side-slip rows coincide (two axles at
    the same x given as different symbols) would give a model wrong near those values."""
    xa, xb = sp.symbols("xa xb", real=True)
    desc = RobotDescription("sym", (BASE,), (), (
        WheelSpec("r", "base", (xa, -0.2), 0.1, 0.01, 0.0, 0.0, True),
        WheelSpec("l", "base", (xb, 0.2), 0.1, 0.01, 0.0, 0.0, True)),
        values={xa: 0.1, xb: 0.1})
    with pytest.raises(DescriptionError, match="not generically"):
        description_system(desc)


# ---------------------------------------------------------------------------------------
# Bad description files: each error names the field
# ---------------------------------------------------------------------------------------
TRAILER_TEXT = shipped_robot_file("trailer").read_text()


def edit(old: str, new: str, count: int = 1) -> str:
    assert old in TRAILER_TEXT, old
    return TRAILER_TEXT.replace(old, new, count)


def drop(line_start: str) -> str:
    lines = TRAILER_TEXT.splitlines()
    index = next(i for i, line in enumerate(lines) if line.startswith(line_start))
    return "\n".join(lines[:index] + lines[index + 1:])


BAD: list[tuple[str, str, tuple[str, ...]]] = [
    ("invalid TOML", TRAILER_TEXT + "\n[[wheel]\n", ("not valid TOML",)),
    ("unknown top-level", 'colour = "red"\n' + TRAILER_TEXT, ("'colour'", "unknown")),
    ("unknown body field", edit("mass = 30.0", "mass = 30.0\nweight = 3"),
     ("'body[0].weight'", "unknown")),
    ("missing body field", drop("yaw_inertia = 1.5"), ("'body[0].yaw_inertia'", "missing")),
    ("missing wheel field", drop("radius = 0.096"),
     ("'wheel[0].radius'", "missing")),
    ("missing joint field", drop("parent_point"), ("'joint[0].parent_point'", "missing")),
    ("string mass", edit("mass = 30.0", 'mass = "30"'), ("'body[0].mass'", "number")),
    ("bool radius", edit("radius = 0.08", "radius = true"), ("'wheel[2].radius'", "number")),
    ("NaN inertia", edit("yaw_inertia = 1.1", "yaw_inertia = nan"),
     ("'body[1].yaw_inertia'", "finite")),
    ("inf com", edit("com = [-0.45, 0.0]", "com = [-inf, 0.0]"),
     ("'body[1].com.x'", "finite")),
    ("zero body mass", edit("mass = 15.0", "mass = 0.0"), ("'body[1].mass'", "positive")),
    ("negative body mass", edit("mass = 30.0", "mass = -30.0"), ("'body[0].mass'", "positive")),
    ("negative yaw inertia", edit("yaw_inertia = 1.5", "yaw_inertia = -1.5"),
     ("'body[0].yaw_inertia'", "non-negative")),
    ("zero radius", edit("radius = 0.096", "radius = 0.0"), ("'wheel[0].radius'", "positive")),
    ("negative spin inertia", edit("spin_inertia = 0.004", "spin_inertia = -0.004"),
     ("'wheel[2].spin_inertia'", "non-negative")),
    ("negative diameter inertia", edit("diameter_inertia = 0.007", "diameter_inertia = -1"),
     ("'wheel[0].diameter_inertia'", "non-negative")),
    ("negative wheel mass", edit("mass = 1.25", "mass = -1.25"),
     ("'wheel[2].mass'", "non-negative")),
    ("point of three", edit("position = [0.0, -0.207]", "position = [0.0, -0.207, 0.0]"),
     ("'wheel[0].position'", "pair")),
    ("point not numbers", edit("child_point = [0.0, 0.0]", 'child_point = ["a", 0.0]'),
     ("'joint[0].child_point.x'", "number")),
    ("driven not bool", edit("driven = true", "driven = 1"),
     ("'wheel[0].driven'", "true or false")),
    ("wheel on unknown body", edit('body = "cart"', 'body = "wagon"'),
     ("'wheel[2].body'", "unknown body 'wagon'")),
    ("joint unknown parent", edit('parent = "tractor"', 'parent = "truck"'),
     ("'joint[0].parent'", "unknown body 'truck'")),
    ("joint unknown child", edit('child = "cart"', 'child = "wagon"'),
     ("'joint[0].child'", "unknown body 'wagon'")),
    ("unknown table", edit("[[joint]]\nkind", "[[joint_]]\nkind"), ("'joint_'", "unknown")),
    ("body without joint", TRAILER_TEXT.split("[[joint]]")[0] + "[[wheel]]"
     + TRAILER_TEXT.split("[[wheel]]", 1)[1],
     ("'body[1]'", "not connected", "'tractor'")),
    ("duplicate body name", edit('name = "cart"', 'name = "tractor"'),
     ("'body[1].name'", "duplicate", "'tractor'")),
    ("wheel named like a body", edit('name = "left"', 'name = "cart"'),
     ("'wheel[1].name'", "duplicate", "'cart'", "body[1]")),
    ("duplicate wheel name", edit('name = "left"', 'name = "right"'),
     ("'wheel[1].name'", "duplicate")),
    ("root as child", edit('child = "cart"', 'child = "tractor"'),
     ("'joint[0].child'", "root")),
    ("second parent", TRAILER_TEXT + '\n[[joint]]\nparent = "tractor"\nchild = "cart"\n'
     "parent_point = [0.0, 0.0]\nchild_point = [0.0, 0.0]\n",
     ("'joint[1].child'", "already has a parent")),
    ("prismatic joint", edit('kind = "revolute"', 'kind = "prismatic"'),
     ("'joint[0].kind'", "revolute")),
    ("no bodies", 'name = "x"\n', ("'body'", "at least one")),
    ("body not a table array", 'name = "x"\nbody = 3\n', ("'body'", "array of tables")),
    ("name not a string", "name = 3\n" + TRAILER_TEXT.split("\n", 6)[6], ("'name'",)),
]


@pytest.mark.parametrize(("text", "words"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_description_is_rejected_naming_the_field(text: str, words: tuple[str, ...]) -> None:
    with pytest.raises(DescriptionError) as info:
        parse_description(text, "bad.toml")
    message = str(info.value)
    assert message.startswith("bad.toml: "), message
    for word in words:
        assert word in message, (word, message)


def test_good_file_parses_and_errors_are_robot_file_errors() -> None:
    desc = parse_description(TRAILER_TEXT, "trailer.toml")
    assert desc == trailer()
    assert [w.name for w in desc.wheels if w.driven] == ["right", "left"]
    assert issubclass(DescriptionError, RobotFileError)
    assert issubclass(DescriptionError, ValueError)


def test_missing_and_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(DescriptionError, match="not found") as info:
        load_description(tmp_path / "nowhere.toml")
    assert "nowhere.toml" in str(info.value)
    bad = tmp_path / "latin1.toml"
    bad.write_bytes(b'name = "caf\xe9"\n')
    with pytest.raises(DescriptionError, match=r"latin1\.toml"):
        load_description(bad)


def test_python_descriptions_are_validated_too() -> None:
    desc = RobotDescription("x", (BASE,), (JointSpec("base", "ghost", (0.0, 0.0)),), ())
    with pytest.raises(DescriptionError, match=r"'joint\[0\]\.child' names unknown body"):
        description_system(desc)


def test_packaged_descriptions_load() -> None:
    loaders: list[Callable[[], RobotDescription]] = [
        lambda: packaged_description("trailer"),
        lambda: load_description(ROBOTS / "drishti_bodies.toml")]
    for load in loaders:
        assert load().bodies
