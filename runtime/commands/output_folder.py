"""An output folder checked before any work is done: a command that would run for a minute
and then fail to write its results says so at once instead."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


class OutputFolderError(ValueError):
    """An output folder that cannot be written; the message names it and why."""


def writable_folder(path: Path, option: str = "--out") -> Path:
    """``path`` created if missing, and checked to be a folder this process can write
    (by creating and removing a file in it). Raises ``OutputFolderError``."""
    if path.exists() and not path.is_dir():
        raise OutputFolderError(f"{option} {path}: exists and is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=path)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputFolderError(f"{option} {path}: cannot write there ({exc.strerror})") from None
    return path


def writable_file(path: Path, option: str = "--out") -> Path:
    """``path`` checked to be a file this process can write: not a folder, and its folder
    (created if missing) writable. Raises ``OutputFolderError``."""
    if path.is_dir():
        raise OutputFolderError(f"{option} {path}: is a folder; name the report file")
    writable_folder(path.parent, option)
    return path
