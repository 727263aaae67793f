"""Line width of the generated C: every line at most :data:`WIDTH` columns.

:func:`format_c` is the C backend's last step. It changes only whitespace between tokens
and inside comments, so the compiled code is the same. Lines that fit are left as the
templates wrote them; a statement (or a template's hand-wrapped statement) with a line
over the width is re-wrapped as a whole:

* breaks fall on a blank outside string and character literals and comments, preferring
  (in order) a blank after a comma or before a binary operator over any other blank (never
  before ``=``), the outermost parenthesis level, and the latest blank that still fills at
  least 60 % of the line; an operator starts its continuation line. A run of
  multiplications too long for a line breaks before a ``*`` or ``/``.
* continuation lines keep the statement's own continuation indent if a template wrapped
  it, else are indented 8 more than the statement (4 at file level, as the prototypes).
* comments are wrapped at blanks: a ``/* ... */`` line continues 3 columns in, a `` * ``
  line of a block comment with the same prefix (4 more after an ``@param`` line), a
  ``//`` comment with ``//``; a trailing comment continues under its own first column,
  or goes above its code if that leaves it too little room.
* preprocessor lines (and their backslash continuations) are never touched: the
  templates keep them short.

Deterministic, idempotent, and the same for any input whose lines already fit.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

WIDTH = 100
_FILL = 0.6  # a break at an outer level must still fill this share of the line
_MIN_TRAILING = 40  # columns a trailing comment needs to stay beside its code

_ASSIGNMENT = re.compile(r"(?:<<|>>|[-+*/%&|^])?=(?!=)")
# A binary operator has blanks on both sides in the generated code (a unary one, or a
# pointer declarator, is followed by its operand).
_BINARY = re.compile(r"[-+*/%<>=!&|^?:]+ ")


@dataclass(frozen=True)
class _Break:
    start: int  # text[start:end] is replaced by a line break (empty for an operator break)
    end: int
    rank: int  # 0: after a comma / before an operator; 1: other blanks; 2: inside a product
    depth: int  # parenthesis level


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip(" "))


def _skip_literal(text: str, i: int) -> int:
    """Index after the string or character literal starting at ``text[i]``."""
    quote, j = text[i], i + 1
    while j < len(text) and text[j] != quote:
        j += 2 if text[j] == "\\" else 1
    return j + 1


def _split_comment(line: str) -> tuple[str, str, bool]:
    """``(code, comment, closed)``: the code before a comment outside literals, the
    comment (from ``/*`` or ``//``; empty if none) and whether it ends on this line.
    Only a comment at the end of the line counts: code after one stays in ``code``."""
    i = 0
    while i < len(line):
        ch = line[i]
        if ch in "\"'":
            i = _skip_literal(line, i)
            continue
        if line.startswith("//", i):
            return line[:i], line[i:], True
        if line.startswith("/*", i):
            end = line.find("*/", i + 2)
            if end < 0:
                return line[:i], line[i:], False
            if line[end + 2 :].strip():  # code after the comment: not a trailing comment
                i = end + 2
                continue
            return line[:i], line[i:].rstrip(), True
        i += 1
    return line, "", True


def _breaks(text: str) -> list[_Break]:
    """Where one logical line of C (no newlines) may break."""
    found: list[_Break] = []
    depth, i, n = 0, 0, len(text)
    while i < n:
        ch = text[i]
        if ch in "\"'":
            i = _skip_literal(text, i)
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            i = n if end < 0 else end + 2
            continue
        if text.startswith("//", i):
            break
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == " ":
            end = i
            while end < n and text[end] == " ":
                end += 1
            if i > 0 and end < n and not _ASSIGNMENT.match(text, end):
                before = text[i - 1]
                assigns = before == "=" and text[i - 2 : i] not in ("==", "<=", ">=", "!=")
                good = not assigns and (before == "," or bool(_BINARY.match(text, end)))
                found.append(_Break(i, end, 0 if good else 1, depth))
            i = end
            continue
        elif (
            ch in "*/"
            and 0 < i < n - 1
            and (text[i - 1].isalnum() or text[i - 1] in "_)]")
            and (text[i + 1].isalnum() or text[i + 1] in "_(")
        ):
            found.append(_Break(i, i, 2, depth))
        i += 1
    return found


def wrap_code(text: str, indent: int, cont: int, width: int = WIDTH) -> list[str]:
    """One logical line of C (``text``, no newline, no leading blanks) as lines of at most
    ``width`` columns: the first indented by ``indent``, the others by ``cont``. A token
    longer than a line stays whole (its line is then over the width)."""
    breaks = _breaks(text)
    lines: list[str] = []
    pos, column = 0, indent
    while True:
        room = width - column
        if len(text) - pos <= room:
            lines.append(" " * column + text[pos:])
            return lines
        fits = [b for b in breaks if pos < b.start and b.start - pos <= room]
        if not fits:
            after = [b for b in breaks if b.start > pos]
            if not after:
                lines.append(" " * column + text[pos:])
                return lines
            chosen = after[0]
        else:
            best_rank = min(b.rank for b in fits)
            fits = [b for b in fits if b.rank == best_rank]
            full = [b for b in fits if b.start - pos >= _FILL * room] or fits
            chosen = min(full, key=lambda b: (b.depth, -b.start))
        lines.append(" " * column + text[pos : chosen.start])
        pos, column = chosen.end, cont


def wrap_words(first: str, cont: str, text: str, width: int = WIDTH) -> list[str]:
    """Comment text as lines ``first + words`` then ``cont + words``, broken at blanks
    (runs of blanks inside a line are kept). A word longer than a line stays whole."""
    parts = re.split(r"( +)", text.strip(" "))
    words, gaps = parts[0::2], ["", *parts[1::2]]
    if len(words) > 1 and words[-1] == "*/":  # a comment's end stays with its last word
        words[-2:], gaps[-1:] = [words[-2] + gaps[-1] + "*/"], []
    lines = [first + words[0]]
    for gap, word in zip(gaps[1:], words[1:], strict=True):
        if len(lines[-1]) + len(gap) + len(word) <= width or lines[-1] == cont:
            lines[-1] += gap + word
        else:
            lines.append(cont + word)
    return lines


def _comment_body(comment: str) -> tuple[str, str]:
    """``("/* ", "text */")`` or ``("// ", "text")``: opener with its blank, and the rest
    with a closing ``*/`` glued to the last word (it never stands alone on a line)."""
    m = re.match(r"(/\*+|//+)( *)", comment)
    assert m is not None
    opener, rest = m.group(0), comment[m.end() :]
    if rest.endswith("*/"):
        rest = rest[:-2].rstrip(" ")
        rest = (rest + " */") if rest else "*/"
    return opener, rest


def _wrap_comment(prefix: str, comment: str, width: int) -> list[str]:
    """A comment starting at column ``len(prefix)`` after ``prefix`` (code or blanks)."""
    opener, rest = _comment_body(comment)
    cont = " " * len(prefix) + ("//" + opener[2:] if opener.startswith("//") else "   ")
    if not rest:
        return [prefix + opener.rstrip(" ")]
    return wrap_words(prefix + opener, cont, rest, width)


def _wrap_comment_line(line: str, width: int) -> list[str]:
    """A line inside a block comment (not its first)."""
    if len(line) <= width:
        return [line]
    m = re.match(r"( *\*+(?!/) ?)( *)(.*)$", line) or re.match(r"( *)()(.*)$", line)
    assert m is not None
    prefix = m.group(1) + m.group(2)
    hang = "    " if m.group(3).startswith("@") else ""
    return wrap_words(prefix, prefix + hang, m.group(3), width)


def _opens_continuation(code: str) -> bool:
    end = code.rstrip()
    return bool(end) and end[-1] not in ";{}:\\"


def _continues(line: str, indent: int) -> bool:
    """Whether ``line`` can be a continuation line of a statement indented ``indent``."""
    stripped = line.strip()
    if not stripped or stripped[0] in "#{}*" or stripped.startswith(("/*", "//")):
        return False
    return _indent(line) > indent and not _split_comment(line)[1]


def _reflow(group: list[str], width: int) -> list[str]:
    """A statement (one or more lines, the last possibly with a trailing comment)."""
    indent = _indent(group[0])
    cont = _indent(group[1]) if len(group) > 1 else (4 if indent == 0 else indent + 8)
    code, comment, _ = _split_comment(group[-1])
    texts = [line.strip(" ") for line in group[:-1]] + [code.strip(" ")]
    text = texts[0]
    for piece in texts[1:]:
        text += piece if text.endswith(("(", "[")) or piece.startswith((")", "]")) else (
            " " + piece
        )
    lines = wrap_code(text, indent, cont, width)
    if not comment:
        return lines
    if len(group) == 1 and len(lines) == 1:
        lines = [code]  # as written, with the blanks that align its comment
    else:
        lines[-1] += " "
    if len(lines[-1]) + _MIN_TRAILING <= width:
        return lines[:-1] + _wrap_comment(lines[-1], comment, width)
    lines[-1] = lines[-1].rstrip(" ")
    return _wrap_comment(" " * indent, comment, width) + lines


def format_c(text: str, width: int = WIDTH) -> str:
    """``text`` (a C source or header) with every line at most ``width`` columns, except
    preprocessor lines and tokens longer than a line, which it leaves as they are."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    in_comment = in_directive = False
    while i < len(lines):
        line = lines[i]
        following = lines[i + 1] if i + 1 < len(lines) else ""
        stripped = line.strip()
        if in_directive or stripped.startswith("#"):
            out.append(line)
            in_directive = line.endswith("\\")
            i += 1
            continue
        if in_comment:
            out.extend(_wrap_comment_line(line, width))
            in_comment = "*/" not in line
            i += 1
            continue
        code, comment, closed = _split_comment(line)
        if not code.strip():  # a comment line
            if len(line) <= width or not comment:
                out.append(line)
            elif closed or not following.strip().startswith("*"):
                out.extend(_wrap_comment(code, comment, width))
            else:  # the first line of a " * " block
                opener, rest = _comment_body(comment)
                out.extend(wrap_words(code + opener, code + " * ", rest, width))
            in_comment = not closed
            i += 1
            continue
        group = [line]
        while (
            _opens_continuation(group[-1])
            and not _split_comment(group[-1])[1]
            and i + len(group) < len(lines)
            and _continues(lines[i + len(group)], _indent(line))
        ):
            group.append(lines[i + len(group)])
        last_comment, last_closed = _split_comment(group[-1])[1:]
        if all(len(g) <= width for g in group) or not last_closed:
            out.extend(group)
        else:
            out.extend(_reflow(group, width))
        in_comment = bool(last_comment) and not last_closed
        i += len(group)
    return "\n".join(out)
