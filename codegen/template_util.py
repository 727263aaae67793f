"""The Jinja2 environment every backend renders through, and the file preamble.

The environment itself is :mod:`modeling.rendering` (strict, whitespace-controlled, layout
only), shared with the robot reports of ``modeling/`` and ``wmr freeze`` of ``runtime/``,
which may not import ``codegen``. Each backend loads templates from its own
``templates/`` directory.
"""

from __future__ import annotations

from pathlib import Path

from modeling.rendering import environment, generated_by, preamble_lines, render, template_label

CODEGEN_DIR = Path(__file__).resolve().parent

__all__ = ["CODEGEN_DIR", "environment", "generated_by", "preamble_lines", "render",
           "template_label"]
