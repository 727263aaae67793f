"""Every generated model, law and plant function of any robot: C (double and float32) and
CasADi against the generated NumPy, at random consistent states.

The functions are enumerated, not listed: each ``__all__`` entry of the robot's generated
``<prefix>_model``, ``<prefix>_laws`` and ``<prefix>_plant`` modules, matched by name with
the prototype ``<prefix>_<name>`` in ``c/<prefix>_<module>.h`` (argument names, which are
inputs — ``const`` — and outputs, the ``#define <PREFIX>_<NAME>_<ARG>_SIZE`` of every array)
and with ``casadi/<name>.casadi`` (inputs by name; a parameter struct is one vector of its
fields in the order of the CasADi manifest ``casadi/*.casadi.txt``). A function missing on
one side is a failing row.

The C prepare-parameters API is checked the same way: ``<prefix>_<name>_prepared`` (C only)
is a row of its own against the NumPy and CasADi ``<name>``, its prepared struct filled from
the same parameters by the module's ``<prefix>_<module>_prepare`` (a function whose only
output is a ``*_prepared_t`` struct; not a row itself).

Inputs, by argument name (sizes from the header):

* a parameter struct: ``<prefix>_params_t`` → the robot's parameters, each scaled by a
  random factor in [0.7, 1.3] per sample, drawn again until SᵀMS is positive definite at
  random configurations (:func:`physical`); ``<prefix>_plant_params_t`` → its plant
  parameters, scaled the same way;
* ``q``, ``q_prev``: random configurations (every coordinate uniform in ±5);
* ``wheel_rates``: random driven-wheel rates η (uniform in ±10 rad/s); ``qdot``:
  q̇ = S(q) η — the dependent velocities through the generated kinematics; ``x`` = (q, η);
* everything else uniform in the range :data:`RANGES` gives for its name (gains, ε, spans,
  window weights positive; ``payload`` = (mass, position…)), else in ±1.

Float32: the inputs (and parameters) are rounded to float32 and the NumPy reference is
evaluated on exactly those rounded values, so the deviation measures float32 arithmetic.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from runtime.tooling.crosscheck.bindings import CModel, casadi_call
from runtime.tooling.crosscheck.deviation import (
    FUNCTION_IMPLS,
    Arr,
    Params,
    Row,
    f32,
    generated_deviation,
    perturbed,
)
from runtime.tooling.crosscheck.targets import Target

MODULES = ("model", "laws", "plant")
PARAM_SPREAD = 0.3  # parameters scaled by a factor in [1 - spread, 1 + spread]
PHYSICAL_CHECKS = 16  # configurations at which drawn parameters must give S^T M S > 0
RANGES: dict[str, tuple[float, float]] = {
    # traction check: a floor and loads that hold the random states' contact forces (the
    # warning path, which writes nothing, is tests/generated/test_contact_forces.py's)
    "mu": (0.5, 1.0), "loads": (3000.0, 6000.0), "shares": (0.0, 1.0),
    "tau": (-30.0, 30.0), "u_prev": (-30.0, 30.0), "qdot_now": (-10.0, 10.0),
    "qdot_then": (-10.0, 10.0), "span": (0.05, 0.3), "e": (-1.0, 1.0), "edot": (-3.0, 3.0),
    "qddot_des": (-5.0, 5.0), "H1hat": (-30.0, 30.0), "k1": (1.0, 8.0), "k2": (1.0, 8.0),
    "p12": (0.05, 2.0), "p22": (0.05, 2.0), "gain": (0.0, 5.0), "eps": (0.02, 0.5),
    "adapt": (0.0, 2.0), "bounds": (0.0, 0.9), "gains": (0.5, 8.0), "minv_norm": (0.1, 10.0),
    "omega": (-20.0, 20.0), "w": (0.0, 1.0), "payload": (-0.5, 0.5),
}  # fmt: skip
_PROTOTYPE = re.compile(r"^\s*(\w+)\s+(\w+)\s*\(([^)]*)\)\s*;", re.MULTILINE)
_SIZE = re.compile(r"^#define\s+(\w+)_SIZE\s+(\d+)", re.MULTILINE)
_MANIFEST_FN = re.compile(r"^(\w+) \(\1\.casadi\)")
_MANIFEST_STRUCT = re.compile(r"^\s+in\s+(\w+): \d+x\d+ \(\w+: ([^)]*)\)")


@dataclass(frozen=True)
class CArg:
    """One argument of a generated C function."""

    name: str
    ctype: str  # without const and *
    output: bool
    size: int  # number of reals (arrays); 0 for a struct

    @property
    def struct(self) -> bool:
        return not self.ctype.endswith("_real_t")


@dataclass(frozen=True)
class Prepare:
    """A C prepare function: ``<prefix>_<name>(inputs..., <ctype> *out)``."""

    name: str
    inputs: tuple[CArg, ...]
    ctype: str  # the prepared struct it fills


@dataclass(frozen=True)
class Function:
    """One generated function: its NumPy callable and argument names, its C prototype.

    ``reference``: the NumPy and CasADi function it is compared with (its own name, or
    ``<name>`` for a C ``<name>_prepared``); ``prepares``: the prepare function of each
    prepared struct it takes, by ctype."""

    module: str
    name: str
    python: Callable[..., Any] | None
    python_args: tuple[str, ...]
    c_args: tuple[CArg, ...] | None
    returns_status: bool
    reference: str = ""
    prepares: tuple[tuple[str, Prepare], ...] = ()

    @property
    def inputs(self) -> tuple[CArg, ...]:
        return tuple(a for a in self.c_args or () if not a.output)

    def value_inputs(self) -> tuple[CArg, ...]:
        """The inputs values are drawn for: a prepared struct stands for its prepare
        function's inputs."""
        prepares = dict(self.prepares)
        out: list[CArg] = []
        for a in self.inputs:
            out += prepares[a.ctype].inputs if a.ctype in prepares else [a]
        return tuple(out)

    @property
    def outputs(self) -> tuple[CArg, ...]:
        return tuple(a for a in self.c_args or () if a.output)


def parse_header(path: Path, prefix: str) -> dict[str, tuple[tuple[CArg, ...], bool]]:
    """Prototypes of a generated header: name (without prefix) -> (arguments, returns a
    status)."""
    text = path.read_text()
    sizes = {m.group(1): int(m.group(2)) for m in _SIZE.finditer(text)}
    out: dict[str, tuple[tuple[CArg, ...], bool]] = {}
    for ret, full, arglist in _PROTOTYPE.findall(text):
        if not full.startswith(f"{prefix}_"):
            continue
        name = full[len(prefix) + 1 :]
        args = []
        for raw in arglist.split(","):
            words = raw.replace("*", " * ").split()
            arg = words[-1]
            ctype = next(w for w in words if w not in ("const", "*"))
            struct = not ctype.endswith("_real_t")
            size = 0 if struct else sizes[f"{prefix}_{name}_{arg}".upper()]
            args.append(CArg(arg, ctype, "const" not in words, size))
        out[name] = (tuple(args), ret != "void")
    return out


@cache
def _manifest_fields(casadi_dir: Path) -> dict[tuple[str, str], tuple[str, ...]]:
    """(function, struct argument) -> its fields in CasADi vector order."""
    fields: dict[tuple[str, str], tuple[str, ...]] = {}
    for manifest in sorted(casadi_dir.glob("*.casadi.txt")):
        current = ""
        for line in manifest.read_text().splitlines():
            if m := _MANIFEST_FN.match(line):
                current = m.group(1)
            elif (m := _MANIFEST_STRUCT.match(line)) and current:
                fields[(current, m.group(1))] = tuple(f.strip() for f in m.group(2).split(","))
    return fields


def _prepare_functions(protos: Mapping[str, tuple[tuple[CArg, ...], bool]]) -> dict[str, Prepare]:
    """The prepare functions among ``protos``, by the ctype of the struct each fills."""
    out: dict[str, Prepare] = {}
    for name, (args, _) in protos.items():
        outputs = [a for a in args if a.output]
        if (name.endswith("_prepare") and len(outputs) == 1 and outputs[0].struct
                and outputs[0].ctype.endswith("_prepared_t")):
            out[outputs[0].ctype] = Prepare(name, tuple(a for a in args if not a.output),
                                            outputs[0].ctype)
    return out


def functions(target: Target) -> list[Function]:
    """Every generated function of the target's model, laws and plant modules (NumPy
    ``__all__`` ∪ C prototypes; a C ``<name>_prepared`` compared with ``<name>``)."""
    out = []
    for module in MODULES:
        py = getattr(target.code, module)
        header = target.c_dir / f"{target.prefix}_{module}.h"
        protos = parse_header(header, target.prefix) if header.is_file() else {}
        prepares = _prepare_functions(protos)
        setup = {p.name for p in prepares.values()}
        exported = set(getattr(py, "__all__", ()))
        names = sorted((exported | set(protos)) - setup)
        for name in names:
            c_args, status = protos.get(name, (None, False))
            used = tuple((a.ctype, prepares[a.ctype]) for a in c_args or ()
                         if not a.output and a.ctype in prepares)
            reference = name.removesuffix("_prepared") if used else name
            fn = getattr(py, reference, None) if reference in exported else None
            args = tuple(inspect.signature(fn).parameters) if fn is not None else ()
            out.append(Function(module, name, fn, args, c_args, status, reference, used))
    return out


@dataclass
class Sample:
    """One random consistent state; further arguments are drawn on first use (and then
    shared by every function of the sample)."""

    rng: np.random.Generator
    p: Params
    pp: Params
    q: Arr
    eta: Arr
    qdot: Arr
    drawn: dict[tuple[str, int], Arr]

    def array(self, name: str, size: int, nq: int) -> Arr:
        if name == "q" and size == nq:
            return self.q
        if name == "qdot" and size == nq:
            return self.qdot
        if name == "wheel_rates" and size == self.eta.size:
            return self.eta
        if name == "x" and size == nq + self.eta.size:
            return np.concatenate([self.q, self.eta])
        key = (name, size)
        if key not in self.drawn:
            if name in ("q", "q_prev"):
                value = self.rng.uniform(-5.0, 5.0, size)
            else:
                lo, hi = RANGES.get(name, (-1.0, 1.0))
                value = self.rng.uniform(lo, hi, size)
                if name == "payload":  # (mass, position...)
                    value[0] = self.rng.uniform(0.0, 20.0)
            self.drawn[key] = value
        return self.drawn[key]


def physical(code: Any, p: Params, rng: np.random.Generator) -> bool:
    """Whether the parameters ``p`` give a positive-definite minimal mass matrix S^T M S
    at :data:`PHYSICAL_CHECKS` random configurations: scaled one by one, the lumped
    parameters of a robot of several bodies can leave the physical set (the generated
    guards then refuse them, rightly), and a comparison needs inputs the code accepts."""
    return all(definite_at(code, p, rng.uniform(-5.0, 5.0, code.nq))
               for _ in range(PHYSICAL_CHECKS))


def definite_at(code: Any, p: Params, q: np.ndarray) -> bool:
    """Whether S^T M S of the parameters ``p`` is positive definite at ``q``."""
    mass = np.asarray(code.model.minimal_mass_matrix(q, p))
    return bool(np.all(np.linalg.eigvalsh(mass.reshape(code.nu, code.nu)) > 0))


def random_samples(target: Target, rng: np.random.Generator, n: int) -> list[Sample]:
    code = target.code
    out = []
    for _ in range(n):
        while True:  # until the sample's own configuration is physical too
            while True:  # until the drawn parameters are physical (mostly the first draw)
                factor = {k: rng.uniform(1 - PARAM_SPREAD, 1 + PARAM_SPREAD)  # sorted: the
                          for k in sorted({*code.params, *code.plant_defaults})}  # same draws
                p = {k: v * factor[k] for k, v in code.params.items()}
                if physical(code, p, rng):
                    break
            pp = {k: v * factor[k] for k, v in code.plant_defaults.items()}
            q = rng.uniform(-5.0, 5.0, code.nq)
            eta = rng.uniform(-10.0, 10.0, code.nu)
            # Five carts' ±30 % draws can be indefinite on a thin set of configurations
            # that the checks above miss (train5); the generated guards rightly refuse them.
            if definite_at(code, p, q):
                break
        out.append(Sample(rng, p, pp, q, eta, code.velocities(q, eta, p), {}))
    return out


def _struct_values(target: Target, arg: CArg, sample: Sample) -> Params:
    if arg.ctype == f"{target.prefix}_params_t":
        return sample.p
    if arg.ctype == f"{target.prefix}_plant_params_t":
        return sample.pp
    raise TypeError(f"{arg.name}: no inputs for struct type {arg.ctype}")


def _inputs(
    target: Target, fn: Function, sample: Sample, impl: str,
    perturb: Mapping[str, Mapping[str, float]], float32: bool,
) -> dict[str, Any]:
    """Input name -> value (a parameter mapping or a flat array) for ``impl``."""
    values: dict[str, Any] = {}
    for arg in fn.value_inputs():
        if arg.struct:
            v: Any = perturbed(_struct_values(target, arg, sample), impl, perturb)
            values[arg.name] = {k: f32(x) for k, x in v.items()} if float32 else v
        else:
            a = sample.array(arg.name, arg.size, target.code.nq)
            values[arg.name] = f32(a) if float32 else a
    return values


def _python(fn: Function, values: Mapping[str, Any]) -> list[Arr]:
    assert fn.python is not None
    result = fn.python(**{name: values[name] for name in fn.python_args})
    outs = result if isinstance(result, tuple) else (result,)
    return [np.ravel(np.asarray(o, dtype=np.float64)) for o in outs]


def _c(cm: CModel, fn: Function, values: Mapping[str, Any]) -> list[Arr]:
    def value(arg: CArg) -> Any:
        return cm.struct(arg.ctype, values[arg.name]) if arg.struct else cm.arr(values[arg.name])

    prepares = dict(fn.prepares)
    args = []
    for arg in fn.inputs:
        if arg.ctype in prepares:  # filled by its prepare function from the same values
            prep = prepares[arg.ctype]
            prepared = cm.ffi.new(f"{arg.ctype} *")
            status = getattr(cm.c, f"{cm.prefix}_{prep.name}")(*map(value, prep.inputs),
                                                               prepared)
            if status != 0:
                raise RuntimeError(f"{cm.prefix}_{prep.name} returned {status}")
            args.append(prepared)
        else:
            args.append(value(arg))
    outs = [cm.out(arg.size) for arg in fn.outputs]
    status = getattr(cm.c, f"{cm.prefix}_{fn.name}")(*args, *outs)
    if fn.returns_status and status != 0:
        raise RuntimeError(f"{cm.prefix}_{fn.name} returned {status}")
    return [cm.read(buf, arg.size) for buf, arg in zip(outs, fn.outputs, strict=True)]


def _casadi(target: Target, fn: Function, values: Mapping[str, Any]) -> list[Arr]:
    from runtime.tooling.crosscheck.bindings import casadi_function

    name = fn.reference or fn.name
    f = casadi_function(target, name)
    fields = _manifest_fields(target.casadi_dir)
    args = []
    for i in range(f.n_in()):
        arg = f.name_in(i)
        v = values[arg]
        if isinstance(v, Mapping):
            v = [v[k] for k in fields[(name, arg)]]
        args.append(v)
    return casadi_call(target, name, *args)


def _missing(fn: Function, target: Target) -> str:
    if fn.python is None:
        return "no NumPy function"
    if fn.c_args is None:
        return "no C prototype"
    if not (target.casadi_dir / f"{fn.reference or fn.name}.casadi").is_file():
        return "no CasADi function"
    if set(fn.python_args) != {a.name for a in fn.value_inputs()}:
        return "arguments differ"
    return ""


def check_functions(
    target: Target, samples: list[Sample], perturb: Mapping[str, Mapping[str, float]]
) -> list[Row]:
    """One row per generated function: the largest deviation of C double, C float32 and
    CasADi from the NumPy reference over ``samples``, per output."""
    cm = {"c64": CModel(target, False), "c32": CModel(target, True)}
    rows = []
    for fn in functions(target):
        row = Row(fn.name)
        rows.append(row)
        missing = _missing(fn, target)
        if missing:
            for impl in FUNCTION_IMPLS:
                row.cells[impl] = generated_deviation(impl)
                row.cells[impl].merge(float("inf"), missing)
            continue
        got: dict[str, list[list[Arr]]] = {impl: [] for impl in FUNCTION_IMPLS}
        want: dict[str, list[list[Arr]]] = {"ref": [], "ref32": []}
        failed: dict[str, str] = {}
        for sample in samples:
            ref = _python(fn, _inputs(target, fn, sample, "ref", perturb, False))
            ref32 = _python(fn, _inputs(target, fn, sample, "ref", perturb, True))
            want["ref"].append(ref)
            want["ref32"].append(ref32)
            for impl in FUNCTION_IMPLS:
                values = _inputs(target, fn, sample, impl, perturb, impl == "c32")
                try:
                    out = _casadi(target, fn, values) if impl == "casadi" else _c(
                        cm[impl], fn, values)
                except RuntimeError as exc:  # an error status where NumPy gave a value
                    failed.setdefault(impl, str(exc).split()[-1])
                    out = [np.full_like(r, np.nan) for r in ref]
                got[impl].append(out)
        for impl in FUNCTION_IMPLS:
            dev = generated_deviation(impl)
            reference = want["ref32" if impl == "c32" else "ref"]
            n_out = len(reference[0])
            if any(len(g) != n_out for g in got[impl]):
                dev.merge(float("inf"), "outputs")
            else:
                names = [a.name for a in fn.outputs] if len(fn.outputs) == n_out else [
                    f"out{i}" for i in range(n_out)]
                for i, name in enumerate(names):
                    dev.add(name, [g[i] for g in got[impl]], [r[i] for r in reference])
            if impl in failed:
                dev.merge(float("inf"), f"status {failed[impl]}")
            row.cells[impl] = dev
    return rows
