"""Where the toolchain's own files are, installed or in a source checkout.

``generated/`` ships inside the package (the shipped robots' code, imported and compiled at
run time). In a source checkout it is the committed folder that ``make model`` regenerates;
in an installed package it sits in site-packages and is never written: commands that write
take ``--out`` or write to a stated default in the working directory.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parent.parent  # holds modeling/, codegen/, generated/


def _generated_folder() -> Path:
    """The folder of the ``generated`` package Python imports (installed, editable or the
    working directory's), else the one beside these packages. Nothing is imported."""
    try:
        spec = importlib.util.find_spec("generated")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations))).resolve()
    return PACKAGE_ROOT / "generated"


SHIPPED_GENERATED = _generated_folder()


def source_checkout() -> bool:
    """True when running from the project's source tree (its pyproject.toml beside the
    packages), False for an installed package (site-packages has none)."""
    pyproject = PACKAGE_ROOT / "pyproject.toml"
    try:
        return 'name = "wmr-toolchain"' in pyproject.read_text(encoding="utf-8")
    except OSError:
        return False


def cache_dir() -> Path:
    """Where compiled objects are cached: ``build/`` of a source checkout; otherwise
    ``$WMR_CACHE_DIR``, else ``$XDG_CACHE_HOME/wmr-toolchain`` (``~/.cache/wmr-toolchain``)."""
    if os.environ.get("WMR_CACHE_DIR"):
        return Path(os.environ["WMR_CACHE_DIR"])
    if source_checkout():
        return PACKAGE_ROOT / "build"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "wmr-toolchain"


def inside(path: Path, folder: Path) -> bool:
    """Whether ``path`` is ``folder`` or lies under it (after resolving both)."""
    p, f = path.resolve(), folder.resolve()
    return p == f or f in p.parents


def default_output(repo_path: str) -> Path:
    """A command's default output: ``repo_path`` of the source checkout (the committed docs
    that ``make`` refreshes), or its last component in the working directory for an
    installed package."""
    if source_checkout():
        return PACKAGE_ROOT / repo_path
    return Path(Path(repo_path).name)
