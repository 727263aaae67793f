"""The CasADi backend as the driver sees it: ``casadi/``, one ``<name>.casadi`` per
function (``casadi.Function.save``) and a text manifest ``<module>.casadi.txt`` per
module."""

from __future__ import annotations

from codegen.backend import RobotTarget
from codegen.backends.casadi.render import render_module


class CasadiBackend:
    """``casadi.Function`` over SX, saved; converted from each function's shared form."""

    name = "casadi"
    folder = "casadi"

    def render(self, target: RobotTarget) -> dict[str, bytes]:
        files: dict[str, bytes] = {}
        for module in target.modules:
            # (the CasADi files name the model's source for every module)
            files.update(render_module(module.functions, module.name,
                                       source=target.model_source))
        return files


BACKEND = CasadiBackend()
