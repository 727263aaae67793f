"""Build the generated C (and runtime C helpers) into a shared library loaded with cffi.

The declarations for cffi come from the generated headers themselves, preprocessed with
an empty ``<math.h>`` (so only our typedefs, enums and prototypes remain and every
``#define`` size is expanded): the Python side can never drift from the C API.
Libraries are cached under ``build/`` by a hash of sources and flags.
"""

from __future__ import annotations

import hashlib
import subprocess
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cffi

ROOT = Path(__file__).resolve().parent.parent
GENERATED_C = ROOT / "generated" / "c"
RUNTIME_C = Path(__file__).resolve().parent / "csrc"
BUILD_DIR = ROOT / "build" / "cffi"
CFLAGS = ("-std=c99", "-O2", "-fPIC", "-shared")
MODULES = ("types", "model", "laws", "plant", "controller", "tdc", "tdroc", "roc", "asmc")


def headers_for(prefix: str) -> tuple[str, ...]:
    """The generated headers of a robot whose C prefix is ``prefix``."""
    return tuple(f"{prefix}_{m}.h" for m in MODULES)


HEADERS = headers_for("wmr")


@dataclass(frozen=True)
class CLibrary:
    """A loaded build: ``ffi`` for types and buffers, ``lib`` for the functions."""

    ffi: Any
    lib: Any
    float32: bool
    path: Path

    @property
    def real(self) -> str:
        return "float" if self.float32 else "double"


def _sources(extra: tuple[Path, ...], c_dir: Path = GENERATED_C,
             prefix: str = "wmr") -> list[Path]:
    return sorted(p for p in c_dir.glob(f"{prefix}_*.c")) + list(extra)


def declarations(
    float32: bool,
    headers: tuple[str, ...] = HEADERS,
    extra_headers: tuple[Path, ...] = (),
    c_dir: Path = GENERATED_C,
    prefix: str = "wmr",
) -> str:
    """The generated headers, preprocessed for ``cffi.FFI.cdef``."""
    with tempfile.TemporaryDirectory() as tmp:
        fake = Path(tmp)
        (fake / "math.h").write_text("")
        src = fake / "all.h"
        includes = [f'#include "{c_dir / h}"' for h in headers]
        includes += [f'#include "{h}"' for h in extra_headers]
        src.write_text("\n".join(includes) + "\n")
        cmd = ["gcc", "-E", "-P", "-nostdinc", f"-I{fake}", f"-I{c_dir}", str(src)]
        if float32:
            cmd.insert(3, f"-D{prefix.upper()}_FLOAT32")
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return text


def build(
    float32: bool = False,
    *,
    extra_sources: tuple[Path, ...] = (),
    extra_headers: tuple[Path, ...] = (),
    flags: tuple[str, ...] = (),
    c_dir: Path = GENERATED_C,
    prefix: str = "wmr",
) -> CLibrary:
    """Compile (or reuse) the library of the generated C in ``c_dir`` (C prefix
    ``prefix``; default: the default robot's) and load it."""
    sources = _sources(extra_sources, c_dir, prefix)
    headers = headers_for(prefix)
    all_flags = (*CFLAGS, *flags, *((f"-D{prefix.upper()}_FLOAT32",) if float32 else ()))
    digest = hashlib.sha256()
    for p in (*sources, *(c_dir / h for h in headers), *extra_headers):
        digest.update(p.name.encode() + p.read_bytes())
    digest.update(" ".join(all_flags).encode())
    BUILD_DIR.mkdir(parents=True, exist_ok=True)
    so = BUILD_DIR / f"lib{prefix}_{digest.hexdigest()[:16]}.so"
    if not so.exists():
        tmp = so.with_suffix(".tmp.so")
        cmd = [
            "gcc",
            *all_flags,
            f"-I{c_dir}",
            f"-I{RUNTIME_C}",
            *map(str, sources),
            "-lm",
            "-o",
            str(tmp),
        ]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        tmp.replace(so)  # atomic: concurrent builds never load a half-written file
    ffi = cffi.FFI()
    ffi.cdef(declarations(float32, headers, extra_headers, c_dir, prefix))
    return CLibrary(ffi, ffi.dlopen(str(so)), float32, so)


def fill_params(
    obj: Any, params: Mapping[str, float], field_names: Mapping[str, str] | None = None
) -> Any:
    """Set a C parameter struct's fields from a mapping with the Python keys, spelled as
    the C backend spells them (``I`` → ``Iz``): ``field_names`` is the robot's generated
    ``C_FIELD_NAMES`` (default: the default robot's)."""
    if field_names is None:
        from runtime.generated_modules import controllers

        field_names = controllers.C_FIELD_NAMES
    for key, value in params.items():
        setattr(obj, field_names.get(key, key), float(value))
    return obj


def params_struct(
    lib: CLibrary,
    params: Mapping[str, float],
    ctype: str = "wmr_params_t",
    field_names: Mapping[str, str] | None = None,
) -> Any:
    """A new C parameter struct from a mapping with the Python keys."""
    return fill_params(lib.ffi.new(f"{ctype} *"), params, field_names)
