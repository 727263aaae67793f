"""What the controller templates need to know about a robot's coordinates and inputs.

The controller step functions (C ``<prefix>_<ctrl>.c``, Python ``controllers.py``) are
the same for every wheeled robot except for sizes, the actuated coordinates, the C
prefix and which kernels exist. A :class:`ControllerLayout` carries exactly that; the
templates read nothing else about the robot (``codegen.generate.layout_for`` builds it from
a ``RobotModel``).

Requirements the templates rely on (checked on construction): the actuated coordinates
are consecutive and ascending in q (the minimal formulation's coordinates are the slice
``q[actuated[0] : actuated[0] + nu]``), there is at least one unactuated coordinate, and
a robot whose minimal ``||Mhat^-1||`` depends on q has no paper formulation (the paper
formulation is generated only for a single rigid body, where it does not).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

NUMBER_WORDS = (
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
)
def words(n: int) -> str:
    """``5`` -> ``"five"`` (digits beyond twelve)."""
    return NUMBER_WORDS[n] if 0 <= n < len(NUMBER_WORDS) else str(n)


def row_span(rows: Iterable[int]) -> str:
    """0-based indices as 1-based rows: ``"1-3"`` for a consecutive run, else a list."""
    ones = [r + 1 for r in rows]
    if len(ones) > 1 and ones == list(range(ones[0], ones[-1] + 1)):
        return f"{ones[0]}-{ones[-1]}"
    return ", ".join(map(str, ones))


def wrap_terms(
    terms: Sequence[str], first: str, cont: str, sep: str, end: str = "", width: int = 100
) -> list[str]:
    """Lines of ``first + t0 + sep + t1 ...`` broken before a separator at ``width``.

    A continuation line starts with ``cont`` followed by the separator stripped of its
    leading blank (``sep=" && "``, ``cont="        "`` gives ``"        && a"``).
    """
    lines = [first + (terms[0] if terms else "")]
    for term in terms[1:]:
        if len(lines[-1]) + len(sep) + len(term) <= width:
            lines[-1] += sep + term
        else:
            lines.append(cont + sep.lstrip() + term)
    lines[-1] += end
    return lines


@dataclass(frozen=True)
class ControllerLayout:
    """A robot's coordinates and inputs as the controller templates see them."""

    prefix: str  # C identifier prefix without the underscore: "wmr"
    nq: int  # generalised coordinates
    nu: int  # inputs = driven wheels
    actuated: tuple[int, ...]  # index in q of each input's coordinate, in input order
    paper: bool  # the paper formulation (n coordinates, tau = B^T u) is generated
    minv_needs_q: bool  # the minimal ||Mhat^-1|| depends on q: evaluated at q every step
    coordinate_names: tuple[str, ...]
    input_names: tuple[str, ...]
    # coordinates whose sin, cos the `_trig` TDE kernels take (robot_functions.trig_angles)
    paper_trig: tuple[int, ...] = ()
    minimal_trig: tuple[int, ...] = ()
    # entries of M-hat the minimal form's `_mhat` kernels take (robot_functions.mhat_kernels;
    # 0: none): the step evaluates M-hat(q) once and keeps it for the next step's (17)
    minimal_mhat: int = 0

    def trig_of(self, formulation: str) -> tuple[int, ...]:
        """The `_trig` kernels' angles of ``formulation`` (() when it has none)."""
        return self.paper_trig if formulation == "paper" else self.minimal_trig

    def mhat_of(self, formulation: str) -> int:
        """Entries of M-hat the `_mhat` kernels of ``formulation`` take (0: none)."""
        return 0 if formulation == "paper" else self.minimal_mhat

    @property
    def history_offset(self) -> int:
        """The first row of q whose rate and input the history for (17) keeps: 0 with the
        paper formulation (it controls every row), else the minimal formulation's offset."""
        return 0 if self.paper else self.offset

    @property
    def history_size(self) -> int:
        """Rows of q(dot) and u the history for (17) keeps (from :attr:`history_offset`):
        the controlled rows of either formulation, all of q with the paper one. A step
        writes only these: a trailer's eight-row history was most of its commit."""
        return self.nq if self.paper else self.nu

    @property
    def keeps_q_prev(self) -> bool:
        """Whether a step reads q(t - h): a formulation whose (17) kernel takes q (neither
        `_trig` nor `_mhat` kernels, which read the sin/cos or M-hat a step keeps)."""
        forms = ("paper", "minimal") if self.paper else ("minimal",)
        return any(not self.trig_of(f) and not self.mhat_of(f) for f in forms)

    @property
    def trig_size(self) -> int:
        """Entries of a TDE controller's trig arrays: sin and cos per angle, the larger
        formulation's (0: no `_trig` kernels)."""
        return 2 * max(len(self.paper_trig) if self.paper else 0, len(self.minimal_trig))

    def __post_init__(self) -> None:
        if not self.prefix.isidentifier() or self.prefix.endswith("_"):
            raise ValueError(f"prefix {self.prefix!r}: a C identifier without a trailing _")
        if len(self.coordinate_names) != self.nq or len(self.input_names) != self.nu:
            raise ValueError("coordinate_names/input_names do not match nq/nu")
        if len(self.actuated) != self.nu or not 0 < self.nu < self.nq:
            raise ValueError(f"need 0 < nu < nq and one actuated coordinate per input: {self}")
        start = self.actuated[0]
        if self.actuated != tuple(range(start, start + self.nu)) or start + self.nu > self.nq:
            raise ValueError(
                f"actuated {self.actuated}: the templates need consecutive, ascending "
                "coordinates inside q (the minimal formulation is a slice of q)"
            )
        if self.paper and self.minv_needs_q:
            raise ValueError(
                "a q-dependent ||Mhat^-1|| is supported for the minimal "
                "formulation only (paper=False)"
            )

    @property
    def PREFIX(self) -> str:
        """``"WMR"`` for prefix ``"wmr"``."""
        return self.prefix.upper()

    @property
    def offset(self) -> int:
        """Where the minimal formulation's coordinates start in q."""
        return self.actuated[0]

    @property
    def unactuated(self) -> tuple[int, ...]:
        """Indices in q of the coordinates no input drives (the rows tau = B^T u drops)."""
        return tuple(i for i in range(self.nq) if i not in self.actuated)

    @property
    def actuated_last(self) -> bool:
        """Whether the actuated coordinates are the last ones of q (the kinematics (31)
        then fill the leading rows of qdot in place)."""
        return self.offset + self.nu == self.nq

    @property
    def state_magic(self) -> str:
        """``STATE_MAGIC``: the prefix's first three letters in ASCII (``0x574d52``, "WMR")."""
        return "0x" + self.PREFIX[:3].encode().hex()

    def words(self, n: int) -> str:
        return words(n)

    def rows(self, indices: Iterable[int]) -> str:
        """1-based rows: ``layout.rows(layout.unactuated)`` is ``"1-3"`` for Drishti."""
        return row_span(indices)

    def scatter(self, name: str, fill: str) -> list[str]:
        """Per coordinate of q: ``name[k]`` for the k-th actuated one, else ``fill``."""
        return [
            f"{name}[{self.actuated.index(i)}]" if i in self.actuated else fill
            for i in range(self.nq)
        ]

    def wrap(
        self, terms: Sequence[str], first: str, cont: str, sep: str, end: str = ""
    ) -> list[str]:
        """``wrap_terms`` for templates (C lines of at most 100 characters)."""
        return wrap_terms(terms, first, cont, sep, end)
