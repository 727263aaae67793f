"""Progress of a long generation: each step named as it starts, and timed.

``wmr model`` on a robot of several bodies takes tens of seconds; a user should see what
it is deriving and generating as it goes, each step with how long it took (``steps``
keeps them for the scaling benchmark). Steps are written to a stream (stderr by default),
so the command's own output (the files written, a ``--check`` diff) stays on stdout.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO


class Progress:
    """Named, timed steps of one robot's generation."""

    def __init__(self, robot: str, stream: TextIO | None = None) -> None:
        self.robot = robot
        self.stream = stream
        self.steps: list[tuple[str, float]] = []

    @contextmanager
    def step(self, what: str) -> Iterator[None]:
        """Time ``what``; announce it first when there is a stream."""
        if self.stream is not None:
            self.stream.write(f"{self.robot}: {what} ...")
            self.stream.flush()
        start = time.perf_counter()
        yield
        seconds = time.perf_counter() - start
        self.steps.append((what, seconds))
        if self.stream is not None:
            self.stream.write(f" {seconds:.1f} s\n")
            self.stream.flush()


def quiet(robot: str = "") -> Progress:
    """A progress that only times (library calls, tests)."""
    return Progress(robot, None)


def to_stderr(robot: str) -> Progress:
    return Progress(robot, sys.stderr)
