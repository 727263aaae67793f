"""Description files as they are published: xacro expanded, comments ignored.

A URDF is often a xacro template (``.urdf.xacro``, or a ``.urdf`` with ``${...}``
properties and ``<xacro:arg>``, as ROBOTIS' TurtleBot3 files are since 2025). It is
expanded here with ``xacro``, the ROS implementation (pure Python, on PyPI), before it is
read; no ROS install is needed. ``$(find PKG)`` (and xacro's ``find(PKG)``) resolve to a
package folder found, in order, under each ``--package-path`` folder or above the file
itself (a folder named PKG, or whose ``package.xml`` names it, or a PKG folder beside
one of the file's parent folders), as a ROS workspace lays packages out.

Whether a file needs expanding is decided on its text without comments: published files
comment xacro out (the TurtleBot3 Burger of 2019 carries a commented-out
``<xacro:include>``), and a namespace declaration alone uses nothing.
"""

from __future__ import annotations

import re
import xml.dom.minidom
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import xacro
from xacro import substitution_args

from modeling.importers.mechanism import ImportFileError

COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)
XACRO_USE = re.compile(r"<\s*/?\s*xacro:|\$\{|\$\(")


def without_comments(text: str) -> str:
    """``text`` with its XML comments removed."""
    return COMMENT.sub("", text)


def uses_xacro(path: Path, text: str) -> bool:
    """Whether the file is a xacro template: by its extension, or by a xacro element or a
    ``${...}``/``$(...)`` substitution outside comments."""
    return path.name.endswith(".xacro") or bool(XACRO_USE.search(without_comments(text)))


def _package_xml_name(folder: Path) -> str | None:
    manifest = folder / "package.xml"
    if not manifest.is_file():
        return None
    found = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text(encoding="utf-8",
                                                                          errors="replace"))
    return found.group(1) if found else None


def _candidates(folder: Path) -> Iterator[Path]:
    """``folder`` and its sub-folders down to two levels (a workspace's ``src/PKG``)."""
    yield folder
    for level in ("*", "*/*"):
        yield from sorted(p for p in folder.glob(level) if p.is_dir())


def find_package(name: str, source: Path, package_path: Sequence[Path]) -> Path | None:
    """The folder of ROS package ``name`` (module docstring), or None."""
    for root in package_path:
        for folder in _candidates(root):
            if folder.name == name or _package_xml_name(folder) == name:
                return folder.resolve()
    for parent in source.resolve().parents:
        if parent.name == name or _package_xml_name(parent) == name:
            return parent
        beside = parent / name
        if beside.is_dir():
            return beside
    return None


MISSING = "/wmr-package-not-found/"  # where $(find PKG) of a package found nowhere points


@contextmanager
def _resolver(source: Path, package_path: Sequence[Path],
              skipped: list[str]) -> Iterator[None]:
    """xacro's package lookup (ROS's ament index, absent here) replaced by
    :func:`find_package` while one file expands; restored afterwards. A package found
    nowhere points to ``MISSING``: published files name sensor
    packages in plugin parameters and include their macros whether or not they use them
    (Clearpath's accessories, off by default), so such an include is skipped and listed in
    ``skipped``; a macro from it that the robot does use fails the expansion by name."""

    def find(name: str) -> str:
        return str(find_package(name, source, package_path) or MISSING + name)

    include_files = xacro.get_include_files

    def includes(spec: str, symbols: object) -> Iterator[str]:
        for filename in include_files(spec, symbols):
            if filename.startswith(MISSING):
                skipped.append(filename.removeprefix(MISSING))
            else:
                yield filename

    saved = substitution_args._eval_find, substitution_args._eval_dict["find"]
    substitution_args._eval_find = find
    substitution_args._eval_dict["find"] = find
    xacro.get_include_files = includes
    try:
        yield
    finally:
        substitution_args._eval_find, substitution_args._eval_dict["find"] = saved
        xacro.get_include_files = include_files


def expand(path: Path, mappings: dict[str, str] | None = None,
           package_path: Sequence[Path] = ()) -> tuple[str, list[str]]:
    """The XML of xacro file ``path`` expanded (``mappings``: its ``xacro:arg`` values)
    and the includes skipped (files of packages found nowhere, as PKG/path); an
    ``ImportFileError`` with xacro's message on a file it cannot expand."""
    skipped: list[str] = []
    with _resolver(path, package_path, skipped):
        try:
            doc = xacro.process_file(str(path.resolve()), mappings=dict(mappings or {}),
                                     verbosity=0)
        except Exception as exc:  # xacro raises its own, expat's, and eval's errors
            message = " ".join(str(exc).split()) or type(exc).__name__
            if skipped:
                message += (f" (includes skipped, their packages found nowhere above the "
                            f"file or under --package-path: {', '.join(skipped)}; give "
                            "the folder holding them with --package-path DIR)")
            raise ImportFileError(f"{path}: xacro could not expand it: {message}") from None
    assert isinstance(doc, xml.dom.minidom.Document)
    return str(doc.toxml()), skipped
