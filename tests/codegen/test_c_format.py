"""Generated C at a readable width: every line of ``generated/**/c/*.{c,h}`` at most 100
columns, and the C backend's formatter (``codegen.backends.c.format``) changes only
whitespace and comment layout: the generated files are its fixed points, it is
idempotent, keeps string literals and preprocessor lines whole, and keeps the token
stream. (That the object code is unchanged was measured when the formatter came in:
``objdump -d`` identical for every generated ``.c``, both robots, double and float32,
x86-64 and Cortex-M4.)
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from codegen.backends.c.format import WIDTH, format_c, wrap_code

GENERATED = Path(__file__).resolve().parents[2] / "generated"
C_FILES = sorted(
    p for p in GENERATED.rglob("*") if p.parent.name == "c" and p.suffix in (".c", ".h")
)


def _tokens(text: str) -> str:
    """The C text without comments and whitespace (strings kept)."""
    out, i = [], 0
    while i < len(text):
        if text[i] == '"':
            j = i + 1
            while text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(text[i : j + 1])
            i = j + 1
        elif text.startswith("/*", i):
            i = text.index("*/", i + 2) + 2
        elif text.startswith("//", i):
            i = text.find("\n", i) if "\n" in text[i:] else len(text)
        else:
            if not text[i].isspace():
                out.append(text[i])
            i += 1
    return "".join(out)


def test_generated_c_files_exist_for_every_robot() -> None:
    folders = {p.parent.relative_to(GENERATED).as_posix() for p in C_FILES}
    assert {"c", "trailer/c"} <= folders
    assert len(C_FILES) > 30


@pytest.mark.parametrize("path", C_FILES, ids=lambda p: p.relative_to(GENERATED).as_posix())
def test_generated_c_lines_fit_the_width(path: Path) -> None:
    text = path.read_text()
    long = [(n, len(line)) for n, line in enumerate(text.splitlines(), 1) if len(line) > WIDTH]
    assert long == [], f"{path}: lines over {WIDTH} columns (line, length): {long[:5]}"
    assert format_c(text) == text  # the backend's last step: formatting again changes nothing


ARGS = "const double *first_argument, const double *second_argument, double *out"
FIRST = [f"first_argument[{k}]" for k in range(6)]
SAMPLE = "\n".join(
    [
        "#define LONG_MACRO(x) ((x)" + "".join(f" + {k}.0" for k in range(1, 14)) + ")",
        "#define CONTINUED { \\",
        "    .a = 1.0, \\",
        "    .b = 2.0 \\",
        "}",
        "/* A stand-alone comment that is much longer than the width of a line, so it has to "
        "be wrapped at blanks. */",
        "typedef struct {",
        "    double field; /* a trailing comment that is long enough to go past the width of "
        "one line of code */",
        "} sample_t;",
        "",
        f"void sample_function_with_a_long_name({ARGS})",
        "{",
        "    const double _t0 = first_argument[0]*second_argument[1] + first_argument[1]"
        "*second_argument[0] - first_argument[2]*(second_argument[2] + second_argument[3]"
        "*second_argument[4]);",
        "    const double _t1 = " + "*".join(FIRST) + ";",
        '    printf("a string literal with  blanks, /* no comment */ and // no comment '
        'either: %f %f\\n", _t0, _t1);',
        "    // a line comment that also goes on well past the width of a line and so it has "
        "to wrap as well, indeed",
        "    if (" + " || ".join(f"!isfinite({a})" for a in FIRST[:3]) + ") {",
        "        out[0] = -_t0;",
        "    }",
        "}",
        "",
    ]
)


def test_formatter_keeps_tokens_literals_and_directives() -> None:
    formatted = format_c(SAMPLE)
    assert _tokens(formatted) == _tokens(SAMPLE)
    assert format_c(formatted) == formatted
    lines = formatted.splitlines()
    for line in lines:
        assert len(line) <= WIDTH or line.startswith("#define LONG_MACRO"), line
    # preprocessor lines and their continuations are left exactly as they were
    assert [ln for ln in lines if ln.startswith("#")] == [
        ln for ln in SAMPLE.splitlines() if ln.startswith("#")
    ]
    assert "    .a = 1.0, \\" in lines and "    .b = 2.0 \\" in lines
    literal = '"a string literal with  blanks, /* no comment */ and // no comment either: '
    assert any(literal + '%f %f\\n",' in ln for ln in lines)  # a literal is never split
    # comments are wrapped, not cut, and stay comments
    assert re.sub(r"\s+", " ", formatted).count("has to be wrapped at blanks. */") == 1
    assert "    // a line comment" in formatted and "\n    // indeed\n" in formatted
    assert "    double field; /* a trailing" in formatted
    assert "\n" + " " * 21 + "code */" in formatted  # under the comment's first column
    # an operator starts a continuation line; continuation indent 8 inside a body
    assert any(re.match(r" {12}[-+] ", ln) for ln in lines)
    assert any(re.match(r" {12}\|\| !isfinite", ln) for ln in lines)


def test_formatter_leaves_lines_that_fit_alone() -> None:
    text = "int f(int a,\n        int b);\n/* short */\nx = a  +  b;\n"
    assert format_c(text) == text


def test_wrap_code_prefers_outer_operators_and_never_breaks_before_assignment() -> None:
    text = "y = a_long_name*(b_long_name + c_long_name + d_long_name) + e_long_name*f_long_name"
    lines = wrap_code(text, 4, 12, width=64)
    assert lines == [
        "    y = a_long_name*(b_long_name + c_long_name + d_long_name)",
        "            + e_long_name*f_long_name",
    ]
    products = "z = " + "*".join(f"factor_{k}" for k in range(12))
    wrapped = wrap_code(products, 0, 8, width=40)
    assert all(len(ln) <= 40 for ln in wrapped)
    assert "".join(wrapped).replace(" ", "") == products.replace(" ", "")
    assert not any(ln.strip().startswith("=") for ln in wrapped)
