"""The generated NumPy-only modules (``generated/python``), importable from anywhere."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # generated/ is not an installed package by design
    sys.path.insert(0, str(ROOT))

from generated.python import controllers, robot, wmr_laws, wmr_model, wmr_plant  # noqa: E402

__all__ = ["controllers", "robot", "wmr_laws", "wmr_model", "wmr_plant"]
