"""Options of the CasADi backend."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CasadiConfig:
    """What the CasADi backend emits.

    ``manifest``: also render ``<module>.casadi.txt`` (text) describing each saved
    function's inputs, outputs and layouts, since a ``.casadi`` file is binary.
    """

    suffix: str = ".casadi"
    manifest: bool = True
