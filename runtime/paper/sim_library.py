"""The paper's robot's generated C with the simulator's RK4 plant helper, as one library.

``runtime/paper/csrc/wmr_sim.c`` integrates the generated plant with wheel friction (viscous and
tanh-smoothed Coulomb) in C, so a simulated sample costs one call from Python.
"""

from __future__ import annotations

from pathlib import Path

from runtime import cbuild

CSRC = Path(__file__).resolve().parent / "csrc"


def build_sim_library(float32: bool = False) -> cbuild.CLibrary:
    """Generated C + the RK4 helper (``runtime.paper.simulate.sim_library`` caches it; tests may
    replace that)."""
    return cbuild.build(
        float32,
        extra_sources=(CSRC / "wmr_sim.c",),
        extra_headers=((CSRC / "wmr_sim.h").resolve(),),
    )
