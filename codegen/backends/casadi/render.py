"""CasADi backend: each FunctionSpec becomes a ``casadi.Function`` over SX.

Layout: every argument is one column vector input/output of the Function, holding its
scalars flat in the same row-major order as the C and Python backends (a params/struct
argument is its fields in order, each row-major). CasADi's own ``reshape`` is
*column-major*, so an (R, C) output ``v`` is ``ca.reshape(v, C, R).T`` in CasADi, or
``np.asarray(v).reshape(R, C)`` in NumPy (row-major).

Outputs of :func:`render` are bytes: ``<name>.casadi`` as written by ``Function.save``,
and (if configured) a UTF-8 text manifest ``<module>.casadi.txt``.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path

import casadi as ca

from codegen import template_util
from codegen.backend import FunctionIR, function_ir
from codegen.backends.casadi.config import CasadiConfig
from codegen.backends.casadi.convert import SXConverter
from codegen.cse import CseResult, count_ops, cse_function
from codegen.layout import argument_size
from codegen.spec import Argument, FunctionSpec

TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"


def to_casadi(spec: FunctionSpec, name: str | None = None) -> ca.Function:
    """``casadi.Function(name or spec.name, inputs, outputs)``; one flat SX column per
    argument, named after the argument."""
    return _function(cse_function(spec), name)


def _function(result: CseResult, name: str | None = None) -> ca.Function:
    """The Function of a CSE of a spec's outputs (no guard rows: CasADi has no status)."""
    spec = result.spec
    inputs = [ca.SX.sym(arg.name, argument_size(arg)) for arg in spec.inputs]
    env = {}
    for arg, sx in zip(spec.inputs, inputs, strict=True):
        for i, symbol in enumerate(arg.all_symbols()):
            env[symbol] = sx[i]
    convert = SXConverter(env)
    for symbol, expr in result.temps:
        convert.bind(symbol, convert(expr))
    outputs = [ca.vertcat(*[convert(e) for e in exprs]) for exprs in result.outputs]
    return ca.Function(
        name or spec.name,
        inputs,
        outputs,
        [a.name for a in spec.inputs],
        [a.name for a in spec.outputs],
    )


def _saved_bytes(function: ca.Function) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "f.casadi"
        function.save(str(path))
        return path.read_bytes()


def _describe(arg: Argument) -> str:
    size = argument_size(arg)
    if arg.kind == "array":
        r, c = arg.shape
        return f"{size}x1 ({r}x{c} row-major)"
    fields = ", ".join(
        f"{f.name}{'' if f.shape == (1, 1) else f'[{f.shape[0]}x{f.shape[1]}]'}" for f in arg.fields
    )
    return f"{size}x1 ({arg.kind}: {fields})"


def render(
    specs: Sequence[FunctionSpec],
    module: str,
    config: CasadiConfig | None = None,
    *,
    source: str = "",
) -> dict[str, bytes]:
    """``{"<name>.casadi": Function.save bytes, ...}`` (+ ``<module>.casadi.txt``)."""
    return render_module([function_ir(s) for s in specs], module, config, source=source)


def render_module(
    functions: Sequence[FunctionIR],
    module: str,
    config: CasadiConfig | None = None,
    *,
    source: str = "",
) -> dict[str, bytes]:
    """:func:`render` from the functions' shared form: each Function is converted from
    ``FunctionIR.plain`` (the CSE of the outputs alone; no CSE here)."""
    config = config or CasadiConfig()
    files: dict[str, bytes] = {}
    for f in functions:
        key = f.name + config.suffix
        if key in files:
            raise ValueError(f"{module}: duplicate function {f.name}")
        files[key] = _saved_bytes(_function(f.plain))
    if config.manifest:
        template = "manifest.txt.jinja"
        manifest = [
            {
                "name": f.name,
                "file": f.name + config.suffix,
                "doc": f.spec.doc.strip().splitlines()[0] if f.spec.doc.strip() else "",
                "equations": ", ".join(f.spec.equations),
                "inputs": [(a.name, _describe(a)) for a in f.spec.inputs],
                "outputs": [(a.name, _describe(a)) for a in f.spec.outputs],
                "ops": (f.ops if f.plain is f.cse else count_ops(f.plain)).comment(),
            }
            for f in functions
        ]
        text = template_util.render(
            TEMPLATE_DIR,
            template,
            preamble=template_util.preamble_lines(source, TEMPLATE_DIR, template),
            module=module,
            functions=manifest,
        )
        files[f"{module}{config.suffix}.txt"] = text.encode()
    return files


def save(
    specs: Sequence[FunctionSpec],
    module: str,
    directory: Path,
    config: CasadiConfig | None = None,
    *,
    source: str = "",
) -> list[Path]:
    """Write :func:`render`'s files into ``directory``; returns their paths."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, data in render(specs, module, config, source=source).items():
        path = directory / name
        path.write_bytes(data)
        paths.append(path)
    return paths


def generate_c(
    specs: Sequence[FunctionSpec],
    directory: Path,
    name: str,
    *,
    prefix: str = "casadi_",
    real: str = "double",
) -> tuple[Path, Path]:
    """CasADi's *own* C code for ``specs`` (``CodeGenerator``), for benchmarks against
    this project's C. Writes ``<name>.c`` and ``<name>.h`` in ``directory``; the
    functions are named ``<prefix><spec.name>`` with CasADi's calling convention
    (``int f(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
    int mem)``). ``real`` sets ``casadi_real`` (``"double"`` or ``"float"``).
    """
    directory.mkdir(parents=True, exist_ok=True)
    generator = ca.CodeGenerator(f"{name}.c", {"with_header": True, "casadi_real": real})
    for spec in specs:
        generator.add(to_casadi(spec, prefix + spec.name))
    generator.generate(str(directory) + "/")
    return directory / f"{name}.c", directory / f"{name}.h"
