"""The repository stands alone: a clone with nothing beside it has every file its documents
link to, and no file names a path of the machine it was written on.

* Links: every Markdown file of the repository (README.md, CHANGELOG.md, docs/, generated/
  and any other), inline links and images ``[text](target)``, reference definitions
  ``[id]: target``, autolinks ``<https://…>`` and HTML ``href``/``src``. Code blocks and
  code spans are not links. A relative target must stay inside the repository, exist and be
  part of it (tracked, or new and not ignored: not .venv or a build output); a ``#fragment``
  into a Markdown file must name one of its headings (GitHub's anchors) or an explicit
  ``<a id>``. Absolute paths and other schemes fail; http(s) links only as listed in
  ``EXTERNAL``.
* Machine paths: every text file of the repository is searched for absolute paths that
  only exist on some machine (home and scratch directories, Windows user folders). A
  legitimate one would go into ``ALLOWED_MACHINE_PATHS`` with its reason; there is none.
"""

from __future__ import annotations

import os
import re
import subprocess
import unicodedata
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[2]

# Every link out of the repository, with the reason it is there. A new one must be added.
EXTERNAL: dict[str, str] = {
    "https://distributed.dask.org": "docs/CAMPAIGN.md: Dask, the campaign's cluster back end",
    "https://doi.org/10.1177/0959651817691641": "docs/PAPER.md: the paper, by its DOI",
}

# (file, text matched) -> why that absolute path is legitimate. Empty: nothing needs one.
ALLOWED_MACHINE_PATHS: dict[tuple[str, str], str] = {}

# What a checkout without git is walked without: git's own files and what .gitignore
# ignores (anywhere, and at the top only).
_IGNORED_ANYWHERE = {".git", ".venv", "__pycache__", ".pytest_cache", ".mypy_cache",
                     ".ruff_cache", ".hypothesis"}
_IGNORED_AT_TOP = {"build", "dist", "out", "reproduction"}

_FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
_CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1", re.DOTALL)
_INLINE = re.compile(
    r"!?\[((?:[^\[\]]|\[[^\]]*\])*)\]"  # [text] (one level of nested brackets)
    r"\(\s*(<[^>\n]*>|[^\s)]*)"  # (target
    r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^)]*\)))?\s*\)"  # optional "title")
)
_REFERENCE = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>\n]*>|\S+)", re.MULTILINE)
_AUTOLINK = re.compile(r"<((?:https?|mailto|ftp|file):[^>\s]+)>")
_HTML_ATTR = re.compile(r"<[a-zA-Z][^>]*?\b(?:href|src)\s*=\s*[\"']([^\"']*)[\"']")
_HEADING = re.compile(r"^ {0,3}#{1,6}\s+(.*?)\s*#*\s*$")
_HTML_ANCHOR = re.compile(r"<a\s[^>]*\b(?:id|name)\s*=\s*[\"']([^\"']+)[\"']")
_SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")

# Absolute paths of some machine: home, scratch and mount directories, macOS temporaries,
# Windows user folders. System paths (/usr/bin/env, /dev/null) are the same everywhere.
MACHINE_PATH = re.compile(
    r"(?<![\w.~$}\-])/(?:work|home|root|Users|tmp|mnt|media|scratch|var/folders)(?![\w.\-])"
    r"|(?<!\w)[A-Za-z]:(?:\\\\?|/)"
    r"(?i:Users|Documents and Settings|Windows|Program Files|ProgramData|home|work|te?mp)"
    r"(?![\w.\-])"
)


# --------------------------------------------------------------------------------------
# The repository's files
# --------------------------------------------------------------------------------------


@cache
def repository_files(root: Path = ROOT) -> frozenset[str]:
    """Paths (relative, '/'-separated) of the files a clone has: tracked, or new and not
    ignored, per git; without git, the tree minus hidden folders and build outputs."""
    try:
        top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=root,
                             capture_output=True, text=True, check=True).stdout.strip()
        if Path(top).resolve() == root.resolve():
            listed = subprocess.run(
                ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                cwd=root, capture_output=True, check=True,
            ).stdout.decode()
            return frozenset(f for f in listed.split("\0") if f and (root / f).is_file())
    except (OSError, subprocess.CalledProcessError):
        pass
    found: set[str] = set()
    for folder, dirs, names in os.walk(root):
        rel = Path(folder).relative_to(root)
        dirs[:] = [d for d in dirs if d not in _IGNORED_ANYWHERE and not d.endswith(".egg-info")
                   and not (rel == Path(".") and d in _IGNORED_AT_TOP)]
        found.update((rel / n).as_posix() for n in names
                     if n != ".git" and not n.endswith((".pyc", ".so", ".o", ".elf")))
    return frozenset(found)


def markdown_files(root: Path = ROOT) -> list[Path]:
    return sorted(root / f for f in repository_files(root) if f.endswith(".md"))


def text_files(root: Path = ROOT) -> Iterator[tuple[str, str]]:
    """(relative path, text) of every file that is UTF-8 text without NUL bytes."""
    for rel in sorted(repository_files(root)):
        data = (root / rel).read_bytes()
        if b"\0" in data:
            continue
        try:
            yield rel, data.decode("utf-8")
        except UnicodeDecodeError:
            continue


# --------------------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------------------


def _without_code(text: str) -> str:
    """The text with fenced code blocks and code spans blanked (line numbers kept)."""
    lines, fence = [], ""
    for line in text.split("\n"):
        m = _FENCE.match(line)
        if fence:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = ""
            lines.append("")
        elif m:
            fence = m.group(1)
            lines.append("")
        else:
            lines.append(line)
    return _CODE_SPAN.sub(lambda m: "\n" * m.group(0).count("\n"), "\n".join(lines))


def links(text: str) -> list[tuple[int, str]]:
    """(line, target) of every link, image, reference definition, autolink and href/src."""
    plain = _without_code(text)
    found = []
    for pattern in (_INLINE, _REFERENCE, _AUTOLINK, _HTML_ATTR):
        group = 2 if pattern is _INLINE else 1
        for m in pattern.finditer(plain):
            found.append((plain.count("\n", 0, m.start()) + 1, m.group(group).strip("<>")))
    return sorted(found)


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: its text lower-cased, without punctuation and symbols
    (letters, marks, digits, '_' and '-' stay), spaces to '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = re.sub(r"<[^>]+>", "", text).replace("`", "")
    out = []
    for ch in text.strip().lower():
        if ch == " ":
            out.append("-")
        elif ch == "-" or unicodedata.category(ch)[0] in "LMN" or unicodedata.category(ch) == "Pc":
            out.append(ch)
    return "".join(out)


def anchors(text: str) -> set[str]:
    """The fragments a Markdown file answers to: its headings' anchors (a repeated one
    numbered -1, -2, … as GitHub does) and explicit <a id/name>."""
    plain = _without_code(text)
    seen: dict[str, int] = {}
    out = set(_HTML_ANCHOR.findall(plain))
    for line in plain.split("\n"):
        m = _HEADING.match(line)
        if not m:
            continue
        base = slug(m.group(1))
        count = seen.get(base, 0)
        seen[base] = count + 1
        out.add(base if count == 0 else f"{base}-{count}")
    return out


def link_problems(md: Path, root: Path = ROOT) -> list[str]:
    """Every link of ``md`` that leaves the repository or does not resolve in it."""
    files = repository_files(root)
    folders = {Path(f).parent.as_posix() for f in files}
    folders |= {p.as_posix() for f in files for p in Path(f).parents}
    name = md.relative_to(root).as_posix()
    problems = []
    for line, target in links(md.read_text(encoding="utf-8")):
        where = f"{name}:{line}: ({target})"
        if not target:
            problems.append(f"{where} empty link")
            continue
        if _SCHEME.match(target):
            if target.startswith(("http://", "https://")):
                if target.split("#")[0].rstrip("/") not in EXTERNAL:
                    problems.append(f"{where} external link not listed in EXTERNAL")
            else:
                problems.append(f"{where} leaves the repository (scheme or drive)")
            continue
        if target.startswith(("/", "\\")):
            problems.append(f"{where} absolute path: leaves the repository")
            continue
        path_part, _, fragment = target.partition("#")
        dest = Path(os.path.normpath(md.parent / unquote(path_part))) if path_part else md
        rel = Path(os.path.relpath(dest, root)).as_posix()
        if rel == ".." or rel.startswith("../"):
            problems.append(f"{where} leaves the repository")
        elif not dest.exists():
            problems.append(f"{where} does not exist")
        elif rel not in files and rel not in folders:
            problems.append(f"{where} is not part of the repository (ignored or a build output)")
        elif fragment and dest.suffix == ".md" and unquote(fragment) not in anchors(
            dest.read_text(encoding="utf-8")
        ):
            problems.append(f"{where} no heading or anchor '#{fragment}' in {rel}")
    return problems


def machine_paths(text: str) -> list[tuple[int, str]]:
    """(line, text) of each absolute path of some machine in ``text``."""
    return [(text.count("\n", 0, m.start()) + 1, m.group(0)) for m in MACHINE_PATH.finditer(text)]


# --------------------------------------------------------------------------------------
# The repository
# --------------------------------------------------------------------------------------


def test_the_documents_are_found() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in markdown_files()}
    for expected in ("README.md", "CHANGELOG.md", "docs/PAPER.md", "docs/CONTROLLERS.md",
                     "generated/MODEL.md", "docs/reproduction/REPORT.md"):
        assert expected in names


@pytest.mark.parametrize("md", markdown_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_link_resolves_inside_the_repository(md: Path) -> None:
    assert link_problems(md) == []


def test_every_listed_external_link_is_used() -> None:
    used = {target.split("#")[0].rstrip("/") for md in markdown_files()
            for _, target in links(md.read_text(encoding="utf-8"))}
    assert set(EXTERNAL) <= used, f"listed but not linked: {sorted(set(EXTERNAL) - used)}"


def test_no_file_names_a_path_of_some_machine() -> None:
    found = [
        f"{rel}:{line}: {match}"
        for rel, text in text_files()
        for line, match in machine_paths(text)
        if (rel, match) not in ALLOWED_MACHINE_PATHS
    ]
    assert found == [], "absolute paths of a machine (use a path relative to the repository):\n" \
        + "\n".join(found)


def test_every_allowed_machine_path_is_still_there() -> None:
    texts = dict(text_files())
    stale = [key for key in ALLOWED_MACHINE_PATHS
             if key[1] not in [m for _, m in machine_paths(texts.get(key[0], ""))]]
    assert stale == []


# --------------------------------------------------------------------------------------
# The checks themselves can fail
# --------------------------------------------------------------------------------------


def _mini_repository(tmp_path: Path) -> Path:
    root = tmp_path / "repo"
    (root / "docs").mkdir(parents=True)
    (root / "docs" / "GUIDE.md").write_text(
        "# Guide\n\n## 2. The step (17) — q\u0308(t − h)\n\n## Guide\n<a id=\"item-3\"></a>\n"
    )
    (root / "data.toml").write_text("x = 1\n")
    (root / "README.md").write_text(
        "[ok](docs/GUIDE.md) ![img](data.toml) [dir](docs/) [top](#readme)\n"
        "[anchor](docs/GUIDE.md#2-the-step-17--q\u0308t--h) [dup](docs/GUIDE.md#guide-1)\n"
        "[html](docs/GUIDE.md#item-3) [wrapped\ntext](data.toml \"title\")\n"
        "```\n[in a fence](missing.md)\n```\n`[in a span](missing.md)`\n"
        "# README\n"
        "[gone](docs/MISSING.md) [out](../outside.toml) [abs](/etc/x.md)\n"
        "[web](https://example.org/page) [mail](mailto:a@b.c) [frag](docs/GUIDE.md#nope)\n"
        "[ref]: ../../elsewhere.md\n"
    )
    return root


def test_link_check_finds_each_kind_of_bad_link(tmp_path: Path) -> None:
    root = _mini_repository(tmp_path)
    problems = link_problems(root / "README.md", root)
    reasons = sorted(p.split(") ", 1)[1] for p in problems)
    assert reasons == sorted([
        "does not exist",
        "leaves the repository",
        "absolute path: leaves the repository",
        "external link not listed in EXTERNAL",
        "leaves the repository (scheme or drive)",
        "no heading or anchor '#nope' in docs/GUIDE.md",
        "leaves the repository",
    ]), problems
    assert any(p.startswith("README.md:10: (docs/MISSING.md)") for p in problems)


def test_link_check_refuses_an_ignored_file(tmp_path: Path) -> None:
    root = _mini_repository(tmp_path)
    subprocess.run(["git", "init", "-q"], cwd=root, check=True)
    (root / ".gitignore").write_text("data.toml\n")
    problems = link_problems(root / "README.md", root)
    assert any("(data.toml) is not part of the repository" in p for p in problems), problems


def test_machine_path_pattern() -> None:
    home, tmp, user = "/" + "home/alice/x.toml", "/" + "tmp/run", "C:" + "\\Users\\al\\x"
    for text in (home, f"see `{tmp}`", f"\"{user}\"", "/" + "work/shared/a.md",
                 "C:/" + "Users/al", "/" + "Users/al/x", "/" + "root", "/" + "var/folders/x"):
        assert machine_paths(text), text
    for text in ("docs/tmp/x", "~/.cache/wmr", "https://example.org/home/x", "/usr/bin/env",
                 "/dev/null", "f\"ROC:\\n\"", "a:\\nwork", "$HOME/tmp", "./tmp/x", "/tmpfile"):
        assert not machine_paths(text), text
