"""One controller instance of a robot's generated C, through cffi.

``<prefix>_<name>_init`` / ``_step`` / ``_step_detail`` / ``_reset`` / ``_check_config``
on a caller-owned state and a configuration (:func:`runtime.bindings.config.controller_config`
fills one), with the step's input and output buffers allocated once. Statuses are the C
``<prefix>_status_t`` enumeration, read from the declarations (never typed here):
:meth:`Controller.status_name`. The one wrapper every command and tool calls the generated
controllers through.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from runtime.bindings import cbuild

STEP_INPUTS = ("q", "qdot", "q_des", "qdot_des", "qddot_des")  # the step's inputs, in order


def status_names(lib: cbuild.CLibrary, prefix: str) -> dict[int, str]:
    """value → name of ``<prefix>_status_t`` (e.g. -5 → ``WMR_ERR_BAD_MEASUREMENT``)."""
    return dict(lib.ffi.typeof(f"{prefix}_status_t").elements)


class Controller:
    """``name``'s generated C for a robot of ``nq`` coordinates and ``nu`` inputs (C prefix
    ``prefix``), with ``config`` (a ``<prefix>_<name>_config_t *``). Not initialised until
    :meth:`init`."""

    def __init__(self, lib: cbuild.CLibrary, prefix: str, name: str, config: Any,
                 nq: int, nu: int) -> None:
        self.lib, self.prefix, self.name, self.config = lib, prefix, name, config
        ffi = lib.ffi
        self.state = ffi.new(f"{prefix}_{name}_state_t *")
        self.state_fields = frozenset(n for n, _ in ffi.typeof(self.state[0]).fields)
        real = f"{prefix}_real_t"
        self.inputs = tuple(ffi.new(f"{real}[{nq}]") for _ in STEP_INPUTS)
        self.tau = ffi.new(f"{real}[{nu}]")
        self.nq, self.nu = nq, nu
        self._fn = {op: getattr(lib.lib, f"{prefix}_{name}_{op}")
                    for op in ("init", "step", "reset", "check_config")}

    def init(self) -> int:
        """``_init``: validate the configuration and derive the state; its status."""
        return int(self._fn["init"](self.state, self.config))

    def reset(self) -> int:
        return int(self._fn["reset"](self.state))

    def check_config(self) -> int:
        return int(self._fn["check_config"](self.config))

    def load(self, values: Sequence[ArrayLike]) -> None:
        """Copy the step's five inputs (q, q̇, q_d, q̇_d, q̈_d) into their C buffers."""
        for buf, v in zip(self.inputs, values, strict=True):
            buf[0:self.nq] = list(np.asarray(v, dtype=np.float64).reshape(-1))

    def step(self, values: Sequence[ArrayLike] | None = None, config: Any = None,
             detail: Any = None, tau: Any = None) -> int:
        """One ``_step`` (``_step_detail`` with a ``<prefix>_error_detail_t *``) on
        ``values`` (default: the inputs already loaded), with ``config`` (default: the
        configuration given at construction); the torque is in :attr:`tau` (or in ``tau``,
        another output buffer, e.g. NULL for a contract test)."""
        if values is not None:
            self.load(values)
        cfg = self.config if config is None else config
        out = self.tau if tau is None else tau
        if detail is None:
            return int(self._fn["step"](self.state, cfg, *self.inputs, out))
        fn = getattr(self.lib.lib, f"{self.prefix}_{self.name}_step_detail")
        return int(fn(self.state, cfg, *self.inputs, out, detail))

    def torque(self) -> NDArray[np.float64]:
        """The last torque written (the drive holds it when no step is called)."""
        return np.array([self.tau[i] for i in range(self.nu)], dtype=np.float64)

    def read(self, field: str, default: Any = 0.0) -> Any:
        """A state field (a number, or a cffi array), or ``default`` if this controller's
        state has no such field."""
        return getattr(self.state, field) if field in self.state_fields else default

    def raw(self) -> bytes:
        """The state's bytes."""
        return bytes(self.lib.ffi.buffer(self.state))

    def status_name(self, status: int) -> str:
        return status_names(self.lib, self.prefix).get(status, f"unknown status {status}")
