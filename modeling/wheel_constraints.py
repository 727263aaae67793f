"""What each row of a wheeled robot's constraint matrix A constrains, declared where the row
is built (a robot description's wheels, or a hand-written model's): the wheel contact
forces (``codegen.contact_forces``) take the wheels of each row from here, and reports
word it with :attr:`WheelConstraint.label`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final, Literal

Kind = Literal["rolling", "no side slip"]
ROLLING: Final = "rolling"
NO_SIDE_SLIP: Final = "no side slip"


@dataclass(frozen=True)
class WheelConstraint:
    """One row of A: the rolling of a wheel (r θ̇_w = v_w · e; ``wheels`` is that wheel)
    or the no side slip of a wheel (v_w · n = 0; ``wheels`` is every wheel the row holds:
    an axle's wheels when one row is theirs)."""

    kind: Kind
    wheels: tuple[str, ...]

    def __post_init__(self) -> None:
        if not self.wheels or (self.kind == ROLLING and len(self.wheels) != 1):
            raise ValueError(f"a {self.kind} row names one wheel or an axle's: {self.wheels}")

    @property
    def label(self) -> str:
        """``rolling of wheel 'right'``, ``no side slip of wheels 'right', 'left' (the axle)``."""
        names = ", ".join(f"'{w}'" for w in self.wheels)
        if len(self.wheels) == 1:
            return f"{self.kind} of wheel {names}"
        return f"{self.kind} of wheels {names} (the axle)"
