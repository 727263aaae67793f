"""C99 backend: ``wmr_types.h`` plus one ``<module>.h``/``<module>.c`` pair per module."""

from codegen.backends.c.config import CConfig, MathMacro, StatusCode
from codegen.backends.c.files import cdef, render, render_all, render_types

__all__ = ["CConfig", "MathMacro", "StatusCode", "cdef", "render", "render_all", "render_types"]
