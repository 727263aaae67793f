"""Build C (the generated code, runtime C helpers, or any sources a test renders) into a
shared library loaded with cffi: the one binding layer between Python and C.

:func:`build` compiles a robot's generated C (cached under ``build/``, per object, by a
hash of source, headers and flags). The declarations for cffi come from the generated
headers themselves, preprocessed with an empty ``<math.h>`` (:func:`declarations`: only our
typedefs, enums and prototypes remain and every ``#define`` size is expanded), so the
Python side can never drift from the C API. Tests that compile C of their own (strict
flags, objects for ``nm``, an executable) use the same pieces: :func:`gcc_command` and
:func:`run_compiler` to compile, :func:`load` (or :func:`build_library`) to bind.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import uuid
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import cffi

from modeling.package_paths import SHIPPED_GENERATED, cache_dir

GENERATED_C = SHIPPED_GENERATED / "c"
# build/ of a source checkout; a user cache for an installed package (never site-packages)
BUILD_DIR = cache_dir() / "cffi"
OBJECT_DIR = BUILD_DIR / "objects"  # one object per source, flags and headers: a regenerated
# module recompiles alone
CFLAGS = ("-std=c99", "-O2")  # and -fPIC -shared (gcc_command, kind="shared")


def headers_for(prefix: str, c_dir: Path = GENERATED_C) -> tuple[str, ...]:
    """The generated headers of a robot whose C prefix is ``prefix``: every
    ``<prefix>_*.h`` of its C folder (the model's modules and one per controller), except
    a configuration ``wmr freeze`` wrote there (``*_frozen.h``, declared only for a build
    that compiles it in: ``extra_headers``)."""
    return tuple(sorted(h.name for h in c_dir.glob(f"{prefix}_*.h")
                        if not h.name.endswith("_frozen.h")))


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


class BuildError(RuntimeError):
    """A compiler command failed (or, when it had to be silent, printed something)."""

    def __init__(self, command: Sequence[str], output: str) -> None:
        super().__init__(f"{' '.join(command)}\n{output}")
        self.command = list(command)
        self.output = output


def compiler() -> str:
    """The C compiler (gcc on the PATH)."""
    return shutil.which("gcc") or "gcc"


def gcc_command(
    sources: Iterable[Path | str],
    output: Path,
    *,
    kind: Literal["shared", "object", "executable"] = "shared",
    flags: Sequence[str] = (),
    include_dirs: Sequence[Path] = (),
    libs: Sequence[str] = (),
) -> list[str]:
    """The gcc command line that compiles (or links) ``sources`` into ``output``: a shared
    library (adds ``-fPIC -shared``), an object (``-c``) or an executable; ``flags`` come
    first, ``libs`` (e.g. ``-lm``) last."""
    mode = {"shared": ["-fPIC", "-shared"], "object": ["-c"], "executable": []}[kind]
    return [compiler(), *flags, *mode, *(f"-I{d}" for d in include_dirs),
            *map(str, sources), *libs, "-o", str(output)]


def run_compiler(commands: Sequence[Sequence[str]], *, jobs: int = 1,
                 silent: bool = False) -> None:
    """Run compiler commands, ``jobs`` at a time; raise :class:`BuildError` if one fails
    (or, with ``silent``, prints anything: a warning the flags did not make an error)."""
    for i in range(0, len(commands), max(1, jobs)):
        procs = [
            (cmd, subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True))
            for cmd in commands[i : i + max(1, jobs)]
        ]
        for cmd, proc in procs:
            out, err = proc.communicate()
            if proc.returncode != 0 or (silent and (out + err).strip()):
                raise BuildError(cmd, out + err)


def load(so: Path, cdef: str | Sequence[str], *, float32: bool = False) -> CLibrary:
    """Bind a compiled library: ``cdef`` (one text or several) declares what Python sees."""
    ffi = cffi.FFI()
    for text in [cdef] if isinstance(cdef, str) else cdef:
        ffi.cdef(text)
    return CLibrary(ffi, ffi.dlopen(str(so)), float32, Path(so))


def build_library(
    sources: Sequence[Path],
    so: Path,
    cdef: str | Sequence[str],
    *,
    float32: bool = False,
    flags: Sequence[str] = (),
    include_dirs: Sequence[Path] = (),
    libs: Sequence[str] = ("-lm",),
) -> CLibrary:
    """Compile ``sources`` into the shared library ``so`` (no cache: for C a caller renders
    itself, e.g. a test's generated module) and bind it with ``cdef``."""
    run_compiler([gcc_command(sources, so, flags=flags, include_dirs=include_dirs,
                              libs=libs)])
    return load(so, cdef, float32=float32)


def declarations(
    float32: bool,
    headers: tuple[str, ...] | None = None,
    extra_headers: tuple[Path, ...] = (),
    c_dir: Path = GENERATED_C,
    prefix: str = "wmr",
    defines: tuple[str, ...] = (),
) -> str:
    """The generated headers, preprocessed for ``cffi.FFI.cdef`` (with empty ``<math.h>``,
    ``<stdint.h>``, ``<stddef.h>`` and ``<string.h>``: cffi declares the fixed-width
    integer types and size_t itself), without the
    ``static inline`` functions a header defines (the double build's sin and cos): a cdef
    only declares. ``defines`` (``-D...``) are those the library was compiled with, so that
    what they declare (a frozen build's configuration) is declared. ``headers`` default:
    :func:`headers_for` ``prefix`` in ``c_dir``."""
    headers = headers_for(prefix, c_dir) if headers is None else headers
    with tempfile.TemporaryDirectory() as tmp:
        fake = Path(tmp)
        (fake / "math.h").write_text("")
        (fake / "float.h").write_text("")
        (fake / "stdint.h").write_text("")  # cffi knows uint32_t and friends itself
        (fake / "stddef.h").write_text("")  # and size_t
        (fake / "string.h").write_text("")  # memcpy: only in static inline bodies, dropped
        src = fake / "all.h"
        includes = [f'#include "{c_dir / h}"' for h in headers]
        includes += [f'#include "{h}"' for h in extra_headers]
        src.write_text("\n".join(includes) + "\n")
        cmd = [compiler(), "-E", "-P", "-nostdinc", f"-I{fake}", f"-I{c_dir}", str(src)]
        if float32:
            cmd.insert(3, f"-D{prefix.upper()}_FLOAT32")
        cmd[3:3] = defines
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    # cffi takes an `extern const` object for a compile-time constant, which a dlopen()ed
    # library cannot give: declared without const, it is read (never written) from memory.
    return without_inline_definitions(text).replace("extern const ", "extern ")


def without_inline_definitions(text: str) -> str:
    """``text`` without its ``static inline`` function definitions (each up to the brace
    that closes its body)."""
    out, pos = [], 0
    while (start := text.find("static inline", pos)) >= 0:
        depth, i = 0, text.index("{", start)
        while True:
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            if depth == 0:
                break
            i += 1
        out.append(text[pos:start])
        pos = i + 1
    out.append(text[pos:])
    return "".join(out)


def build(
    float32: bool = False,
    *,
    extra_sources: tuple[Path, ...] = (),
    extra_headers: tuple[Path, ...] = (),
    flags: tuple[str, ...] = (),
    c_dir: Path = GENERATED_C,
    prefix: str = "wmr",
    extra_defines: tuple[str, ...] = (),
) -> CLibrary:
    """Compile (or reuse) the library of the generated C in ``c_dir`` (C prefix
    ``prefix``; default: the default robot's) and load it. Objects are cached per source
    (with its flags and every header it may include), so a modified or regenerated module
    recompiles alone; the library is cached by its objects. ``extra_defines`` (``-D...``)
    apply to the extra sources and headers only (a runtime helper compiled for this
    robot's prefix), so the generated objects are shared with every other build."""
    sources = _sources(extra_sources, c_dir, prefix)
    headers = headers_for(prefix, c_dir)
    all_flags = (*CFLAGS, *flags, *((f"-D{prefix.upper()}_FLOAT32",) if float32 else ()))
    # Every header a source may include: any change recompiles every object. An extra
    # source finds its own headers (and an extra header's folder is searched too).
    included = hashlib.sha256()
    for h in (*sorted(c_dir.glob("*.h")), *extra_headers):
        included.update(h.name.encode() + h.read_bytes())
    include_dirs = tuple(dict.fromkeys((c_dir, *(Path(h).parent for h in extra_headers))))
    objects, compile_cmds, renames = [], [], []
    extra = set(extra_sources)
    for src in sources:
        src_flags = (*all_flags, *(extra_defines if src in extra else ()))
        key = included.copy()
        key.update(src.name.encode() + src.read_bytes() + " ".join(src_flags).encode())
        obj = OBJECT_DIR / f"{prefix}_{src.stem}_{key.hexdigest()[:16]}.o"
        objects.append(obj)
        if not obj.exists():
            tmp = obj.with_suffix(f".{uuid.uuid4().hex[:8]}.tmp.o")
            compile_cmds.append(gcc_command([src], tmp, kind="object",
                                            flags=(*src_flags, "-fPIC"),
                                            include_dirs=include_dirs))
            renames.append((tmp, obj))
    OBJECT_DIR.mkdir(parents=True, exist_ok=True)
    run_compiler(compile_cmds, jobs=min(4, os.cpu_count() or 1))
    for tmp, obj in renames:
        tmp.replace(obj)  # atomic: concurrent builds never use a half-written file
    digest = hashlib.sha256(" ".join(o.name for o in objects).encode())
    so = BUILD_DIR / f"lib{prefix}_{digest.hexdigest()[:16]}.so"
    if not so.exists():
        tmp = so.with_suffix(f".{uuid.uuid4().hex[:8]}.tmp.so")
        run_compiler([gcc_command(objects, tmp, kind="shared", libs=("-lm",))])
        tmp.replace(so)
    defines = (*(f for f in flags if f.startswith("-D")), *extra_defines)
    return load(so, declarations(float32, headers, extra_headers, c_dir, prefix, defines),
                float32=float32)


def fill_params(
    obj: Any, params: Mapping[str, float], field_names: Mapping[str, str] | None = None
) -> Any:
    """Set a C parameter struct's fields from a mapping with the Python keys, spelled as
    the robot's parameter table spells them in C (Drishti's ``I`` → ``Iz``): ``field_names``
    is the robot's generated ``C_FIELD_NAMES`` (default: the default robot's)."""
    if field_names is None:
        from runtime.bindings.generated import controllers

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
