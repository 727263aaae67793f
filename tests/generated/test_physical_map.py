"""The generated map from physical quantities to base parameters (issue 48) against a fresh
derivation: a description with the drawn masses, inertias and centres of mass (the drawn
payload merged into the root body by the parallel-axis theorem, as the MuJoCo plant
builds it), its kinetic energy derived in numbers and read off at the base parameters'
monomials. NumPy and CasADi agree with it to 1e-12 (the C is compared with NumPy by the
cross-check)."""

from __future__ import annotations

from dataclasses import replace

import casadi
import numpy as np
import pytest
import sympy as sp

from modeling.base_parameters import split_terms
from modeling.description import description_kinetic_energy, load_description
from modeling.description.kinematics import coordinates
from modeling.description.schema import symbolize
from modeling.robot_model import described_model
from runtime.bindings.generated import GENERATED, load_robot_code
from runtime.bindings.physical_bounds import physical_model
from runtime.campaign.physical_draws import physical_layout

ROBOTS = ("trailer", "trailer2")
DRAWS = 3


def _fresh_beta(name: str, values: dict[str, float]) -> dict[str, float]:
    """β of the robot with ``values``, derived afresh from a numeric description."""
    path = f"modeling/robots/{name}/{name}.toml"
    desc = load_description(path)
    code = load_robot_code(name)
    robot = physical_layout(code, values)  # the payload merged into the root body
    bodies = tuple(replace(b, mass=rb.mass, yaw_inertia=rb.yaw_inertia, com=rb.com)
                   for b, rb in zip(desc.bodies, robot.bodies, strict=True))
    wheels = tuple(replace(w, mass=rw.mass, spin_inertia=rw.spin_inertia,
                           diameter_inertia=rw.diameter_inertia)
                   for w, rw in zip(desc.wheels, robot.wheels, strict=True))
    drawn = replace(desc, bodies=bodies, wheels=wheels)
    t = description_kinetic_energy(drawn, numeric=True)
    coords = coordinates(symbolize(drawn, numeric=True))
    pieces = split_terms(t, {*coords.q, *coords.qdot})
    model = described_model(path)
    out = {}
    for p in model.params:
        if p.key.startswith("radius_"):
            continue
        # the base parameter's monomial and natural factor, from its description string
        mono = _monomials(model)[p.key]
        out[p.key] = float(mono[1] * pieces.get(mono[0], sp.S.Zero))
    return out


def _monomials(model: object) -> dict[str, tuple[sp.Expr, int]]:
    from modeling.base_parameters import reduce_to_base
    from modeling.description import description_system

    system = description_system(model.system.description)  # type: ignore[attr-defined]
    names = dict(zip(system.qdot, system.coordinate_names, strict=True))
    red = reduce_to_base(system.kinetic_energy, [*system.q, *system.qdot], names)
    return {str(b.symbol): (b.monomial, b.natural) for b in red.parameters}


def _draws(name: str) -> list[dict[str, float]]:
    pm = physical_model(load_robot_code(name))
    rng = np.random.default_rng(48)
    out = []
    for _ in range(DRAWS):
        values = {}
        for k, v in zip(pm.keys, pm.nominal, strict=True):
            if k.startswith("com_"):
                values[k] = v + rng.uniform(-0.1, 0.1)
            elif k == "payload_mass":
                values[k] = rng.uniform(0.5, 8.0)
            elif k.startswith("payload_"):
                values[k] = rng.uniform(-0.2, 0.2)
            else:
                values[k] = v * rng.uniform(0.6, 1.4)
        out.append(values)
    return out


@pytest.mark.parametrize("name", ROBOTS)
def test_map_matches_a_fresh_derivation(name: str) -> None:
    code = load_robot_code(name)
    pm = physical_model(code)
    fn = casadi.Function.load(str(GENERATED / name / "casadi"
                                  / "plant_params_from_physical.casadi"))
    for values in _draws(name):
        x = np.array([values[k] for k in pm.keys])
        fresh = _fresh_beta(name, values)
        numpy_out = np.ravel(code.plant.plant_params_from_physical(x))
        casadi_out = np.ravel(np.asarray(fn(x)))
        terms_out = pm.beta(x)[0]
        want = np.array([fresh[k] for k in pm.outputs])
        scale = np.maximum(1.0, np.abs(want))
        for got in (numpy_out, casadi_out, terms_out):
            assert np.max(np.abs(got - want) / scale) < 1e-12, (name, pm.outputs, got, want)


def test_map_at_the_robot_files_values_is_its_model() -> None:
    code = load_robot_code("trailer3")
    pm = physical_model(code)
    params = pm.params(np.array(pm.nominal))
    for k, v in code.params.items():
        assert params[k] == pytest.approx(v, rel=1e-13, abs=1e-15), k
