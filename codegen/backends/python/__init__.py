"""NumPy-only Python backend: one ``<module>.py`` of plain functions."""

from codegen.backends.python.config import PythonConfig
from codegen.backends.python.render import render

__all__ = ["PythonConfig", "render"]
