"""CasADi backend: SymPy -> ``casadi.SX`` -> saved ``casadi.Function`` files."""

from codegen.backends.casadi.config import CasadiConfig
from codegen.backends.casadi.render import generate_c, render, save, to_casadi

__all__ = ["CasadiConfig", "generate_c", "render", "save", "to_casadi"]
