"""A controller's configuration frozen into firmware: ``<prefix>_<name>_frozen.h``.

A build of ``<prefix>_<name>.c`` with ``-D<PREFIX>_<NAME>_FROZEN`` takes its configuration
from that header: ``_init`` copies the state the header holds, and a step checks only that
it was handed ``&<prefix>_<name>_frozen_config``. The image then carries no configuration
checks, fingerprint or derivation (P of (20), the weights and ‖M̂⁻¹‖ of (25)). What makes
that safe is done here, on the host, with the generated C itself (through cffi, in the
precision of the firmware): ``_check_config_detail`` validates the configuration and
``_init`` derives the state, so the frozen build starts from the very bytes a run-time
``_init`` would have written.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from codegen.template_util import CODEGEN_DIR, generated_by, render, template_label
from runtime import cbuild
from runtime.generated_modules import RobotCode

C_TEMPLATES = CODEGEN_DIR / "backends" / "c" / "templates"  # the C backend's (no SymPy import)
TEMPLATE = "frozen.h.jinja"


class FreezeError(ValueError):
    """A configuration the generated C refuses; the message names the status and field."""


@dataclass(frozen=True)
class Frozen:
    """A rendered header and where it goes."""

    filename: str  # <prefix>_<name>_frozen.h
    text: str


def real_literal(x: float, float32: bool) -> str:
    """``x`` as an exact C literal (hexadecimal; ``f`` suffix for float32 builds)."""
    if not math.isfinite(x):
        raise FreezeError(f"{x} cannot be frozen: not finite")
    mantissa, exponent = float(x).hex().split("p")
    mantissa = mantissa.rstrip("0").rstrip(".")  # 0x1.8000000000000 -> 0x1.8, 0x1.0 -> 0x1
    return f"{mantissa}p{exponent}" + ("f" if float32 else "")


def _value(ffi: Any, ctype: Any, value: Any, float32: bool) -> str:
    if ctype.kind == "struct":
        return "{" + ", ".join(
            f".{name} = {_value(ffi, f.type, getattr(value, name), float32)}"
            for name, f in ctype.fields
        ) + "}"
    if ctype.kind == "array":
        return "{" + ", ".join(_value(ffi, ctype.item, value[i], float32)
                               for i in range(ctype.length)) + "}"
    name = ctype.cname
    if name in ("float", "double"):
        return real_literal(float(value), float32)
    if name == "uint32_t":
        return f"{int(value)}u"
    if name == "long":
        return f"{int(value)}L"
    if name == "int":
        return str(int(value))
    raise FreezeError(f"cannot write a C value of type {name}")


def initializer_lines(ffi: Any, struct: Any, float32: bool) -> list[str]:
    """A C99 designated initializer of the struct behind the pointer ``struct``: one line per
    field, every entry exact."""
    ctype = ffi.typeof(struct[0])
    fields = [f".{name} = {_value(ffi, f.type, getattr(struct, name), float32)}"
              for name, f in ctype.fields]
    return ["{", *[f"    {line}," for line in fields[:-1]], f"    {fields[-1]}", "}"]


def code_hash(c_dir: Path, prefix: str) -> str:
    """sha256 of the generated C (sources and headers) a header is frozen with."""
    digest = hashlib.sha256()
    for path in sorted(c_dir.glob(f"{prefix}_*.[ch]")):
        if not path.name.endswith("_frozen.h"):
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _error(code: RobotCode, detail: Any) -> str:
    statuses = {v: k for k, v in code.controllers.STATUS.items()}
    fields = {v: k for k, v in code.controllers.FIELDS.items()}
    field = fields.get(int(detail.field), str(detail.field)).lower()
    where = f"{field}[{detail.index}]" if detail.index >= 0 else field
    return f"{statuses.get(int(detail.status), str(detail.status))} (field {where})"


def freeze(lib: cbuild.CLibrary, code: RobotCode, name: str, config: Any,
           made_from: Sequence[str] = ()) -> Frozen:
    """Validate ``config`` (a ``<prefix>_<name>_config_t *`` of ``lib``) with the generated
    ``_check_config_detail``, run ``_init`` on it, and render the frozen header. Raises
    :class:`FreezeError` naming the status and field the C refused."""
    pre, ffi = code.prefix, lib.ffi
    detail = ffi.new(f"{pre}_error_detail_t *")
    status = getattr(lib.lib, f"{pre}_{name}_check_config_detail")(config, detail)
    if status != 0:
        raise FreezeError(f"the {name} configuration is refused: {_error(code, detail)}")
    state = ffi.new(f"{pre}_{name}_state_t *")
    status = getattr(lib.lib, f"{pre}_{name}_init")(state, config)
    if status != 0:  # check_config accepted it: init cannot refuse it
        raise FreezeError(f"{pre}_{name}_init refused a configuration check_config accepted "
                          f"(status {status})")
    filename = f"{pre}_{name}_frozen.h"
    text = render(
        C_TEMPLATES, TEMPLATE,
        preamble=(f"{generated_by().replace('`wmr model`', '`wmr freeze`')} DO NOT EDIT: "
                  "rerun `wmr freeze`.", f"Template: {template_label(C_TEMPLATES, TEMPLATE)}"),
        pre=pre, PRE=pre.upper(), controller=name, robot=code.name, made_from=list(made_from),
        real=lib.real, float32=lib.float32, code_hash=code_hash(code.c_dir, pre),
        formulation=int(config.formulation),
        config_lines=initializer_lines(ffi, config, lib.float32),
        state_lines=initializer_lines(ffi, state, lib.float32),
    )
    return Frozen(filename, text)
