"""Where an image's generated code goes: each ``wmr_*`` function of a linked image in one
part of the controller's contract (configuration checks, the configuration comparison, input
checks, the step's bookkeeping, the control math), so that a size goal can be weighed against what
the code does. Classified by name; a function no part claims is ``unclassified`` (a test
keeps that empty, so a new generated function has to be placed).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

from modeling.controllers import FORMULATIONS


@dataclass(frozen=True)
class Part:
    name: str
    when: str  # when the part runs
    pattern: re.Pattern[str]  # matches a function name without its prefix


PARTS: tuple[Part, ...] = (
    Part("configuration checks", "at _init; in a step only when the configuration changed",
         re.compile(r"(\w+_)?check_config(_detail)?|check_base_config|check_nominal"
                    r"|positive(_at_most)?|nonnegative_at_most|within|lyapunov_p")),
    Part("configuration comparison", "every step (detects a changed configuration)",
         re.compile(r"\w+_config_unchanged|real_bits")),
    Part("configuration-derived data, init, reset", "at _init and _reset",
         re.compile(r"\w+_(init|reset|clear)|controller_p|\w+_minv_norm|window_weights"
                    r"|\w+_k_\w+_keep")),
    Part("input checks, error detail", "every step",
         re.compile(r"check_step_inputs|fail|\w+_inputs_bounded")),
    Part("step: history, commit, saturation", "every step",
         re.compile(r"\w+_step(_detail|_as)?|saturate|cap_gain|push_history|controlled_slice")),
    Part("control law and estimators (from SymPy)", "every step",
         re.compile(rf"(\w+_k_)?(({'|'.join(FORMULATIONS)})_\w+|\w+_weighted_gain)"
                    r"|norm(\d+|_scaled)|sincos_(bounded|checked|kernel)|(sin|cos)(_bounded)?")),
)
UNCLASSIFIED = "unclassified"


def part_of(function: str, prefix: str = "wmr_") -> str:
    """The name of the part a generated function (``wmr_...``) belongs to."""
    bare = function.removeprefix(prefix).split(".")[0]  # gcc's clones: f.isra.0, f.part.0
    for part in PARTS:
        if part.pattern.fullmatch(bare):
            return part.name
    return UNCLASSIFIED


def budget(functions: Mapping[str, int], prefix: str = "wmr_") -> dict[str, int]:
    """Bytes of code per part (every part listed, in :data:`PARTS` order; ``unclassified``
    only when some function is)."""
    out = {part.name: 0 for part in PARTS}
    for name, size in functions.items():
        key = part_of(name, prefix)
        out[key] = out.get(key, 0) + size
    return out
