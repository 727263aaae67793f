"""One package per target language, and the registry the driver iterates.

Each entry of :data:`REGISTERED` is a module exposing ``BACKEND``, an object satisfying
:class:`codegen.backend.Backend`. ``python -m codegen`` renders every robot through every
registered backend, in this order; adding a backend is its own package plus one line here.
"""

from __future__ import annotations

import importlib

from codegen.backend import Backend

REGISTERED: tuple[str, ...] = (
    "codegen.backends.c.backend",
    "codegen.backends.python.backend",
    "codegen.backends.casadi.backend",
)


def registered() -> tuple[Backend, ...]:
    """The registered backends (imported on first use), checked against the protocol."""
    found: list[Backend] = []
    for path in REGISTERED:
        backend = getattr(importlib.import_module(path), "BACKEND", None)
        if not isinstance(backend, Backend):
            raise TypeError(f"{path}.BACKEND is not a codegen.backend.Backend: {backend!r}")
        found.append(backend)
    for attr in ("name", "folder"):
        values = [getattr(b, attr) for b in found]
        if len(set(values)) != len(values):
            raise ValueError(f"registered backends share a {attr}: {values}")
    return tuple(found)
