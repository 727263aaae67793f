"""Apply mutants one at a time to a copy of the project and run the tests meant to catch
each: does the suite fail when the code is wrong?

A :class:`Mutant` is a realistic one-line bug: an exact snippet of one file (it must occur
there exactly once, or the mutant is *stale* and reported so, never skipped silently), what
replaces it, and the test files (or node ids) that should catch it. The project is copied
once (the files git tracks, plus ``build/``'s compiled cache, so nothing is rebuilt that
the mutant does not touch); each mutant is written into the copy, its tests run there with
``pytest -x``, and the file is restored before the next. The working tree is never
written.

Verdicts: ``caught`` (pytest reported failed tests: exit 1), ``error`` (the tests could not
run: collection or import error, exit 2–4: the mutant broke the module outright, which is
caught too, but by accident), ``uncaught`` (exit 0), ``stale`` (the snippet is not in the
file once), ``timeout``.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

CAUGHT, ERROR, UNCAUGHT, STALE, TIMEOUT = "caught", "error", "uncaught", "stale", "timeout"


@dataclass(frozen=True)
class Mutant:
    """One bug: ``original`` (exactly once in ``path``) becomes ``replacement``; ``tests``
    should fail. ``why``: what the bug would do to a user, in a few words."""

    name: str
    path: str  # relative to the project root
    original: str
    replacement: str
    tests: tuple[str, ...]
    why: str


@dataclass(frozen=True)
class Result:
    mutant: Mutant
    verdict: str
    seconds: float
    detail: str  # the first failing test, or why the mutant is stale

    @property
    def caught(self) -> bool:
        return self.verdict in (CAUGHT, ERROR)


def occurrences(root: Path, m: Mutant) -> int:
    """How often ``m.original`` occurs in its file (0 when the file is missing)."""
    path = root / m.path
    return path.read_text(encoding="utf-8").count(m.original) if path.is_file() else 0


def stale(root: Path, mutants: Iterable[Mutant]) -> list[str]:
    """The mutants whose snippet is not in their file exactly once, with the count."""
    return [f"{m.name}: {m.path} holds its snippet {n} times" for m in mutants
            if (n := occurrences(root, m)) != 1]


def tracked_files(root: Path) -> list[str]:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True,
                         check=True).stdout.decode()
    return [p for p in out.split("\0") if p]


def copy_project(root: Path, into: Path) -> Path:
    """A copy of the project's tracked files as they are in the working tree (uncommitted
    edits included), and its ``build/`` cache; returns the copy's root."""
    dest = into / "project"
    for rel in tracked_files(root):
        src = root / rel
        if src.is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
    if (root / "build").is_dir():
        shutil.copytree(root / "build", dest / "build", symlinks=True)
    return dest


def _first_failure(output: str) -> str:
    for line in output.splitlines():
        if line.startswith(("FAILED ", "ERROR ")):
            return line.split(" - ")[0][:160]
    return output.strip().splitlines()[-1][:160] if output.strip() else ""


def run_mutant(copy: Path, m: Mutant, python: str = sys.executable,
               timeout: float = 900.0) -> Result:
    """Apply ``m`` in ``copy``, run its tests, restore the file."""
    path = copy / m.path
    n = occurrences(copy, m)
    if n != 1:
        return Result(m, STALE, 0.0, f"snippet found {n} times in {m.path}")
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace(m.original, m.replacement), encoding="utf-8")
    start = time.perf_counter()
    try:
        proc = subprocess.run([python, "-m", "pytest", "-x", "-q", "-p", "no:xdist",
                               "-p", "no:cacheprovider", *m.tests], cwd=copy,
                              capture_output=True, text=True, timeout=timeout, check=False)
        verdict = {0: UNCAUGHT, 1: CAUGHT}.get(proc.returncode, ERROR)
        detail = _first_failure(proc.stdout + proc.stderr)
    except subprocess.TimeoutExpired:
        verdict, detail = TIMEOUT, f"no result within {timeout:g} s"
    finally:
        path.write_text(text, encoding="utf-8")
    return Result(m, verdict, time.perf_counter() - start, detail)


def run_all(root: Path, mutants: Sequence[Mutant],
            progress: Callable[[int, Result], None] | None = None,
            python: str = sys.executable) -> list[Result]:
    """Every mutant in a fresh copy of ``root`` (made once), in order."""
    results: list[Result] = []
    with tempfile.TemporaryDirectory(prefix="wmr-mutation-") as tmp:
        copy = copy_project(root, Path(tmp))
        for k, m in enumerate(mutants):
            r = run_mutant(copy, m, python)
            results.append(r)
            if progress is not None:
                progress(k, r)
    return results


def report(results: Sequence[Result]) -> str:
    """A Markdown table, one row a mutant, and the count."""
    caught = sum(r.caught for r in results)
    lines = [f"{caught} of {len(results)} mutants caught "
             f"({sum(r.verdict == UNCAUGHT for r in results)} uncaught, "
             f"{sum(r.verdict == STALE for r in results)} stale, "
             f"{sum(r.verdict == TIMEOUT for r in results)} timed out).", "",
             "| mutant | file | verdict | by | s | what it would do |",
             "|---|---|---|---|---|---|"]
    for r in results:
        by = r.detail.replace("|", "\\|") if r.verdict != UNCAUGHT else ""
        lines.append(f"| {r.mutant.name} | `{r.mutant.path}` | {r.verdict} | {by} | "
                     f"{r.seconds:.0f} | {r.mutant.why} |")
    return "\n".join(lines) + "\n"
