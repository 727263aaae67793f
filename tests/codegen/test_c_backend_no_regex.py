"""The C backend decides what to generate from the function IR and the controllers'
declarations, never by reading back what it rendered.

* During one robot's generation every C template is rendered exactly once per file it
  writes (each file names its template in its preamble), and a fragment (a template no
  file names, spliced into another) at most once: no render whose text is thrown away
  after being searched, as the controllers and the types header once were.
* No module of ``codegen/`` uses ``re`` but the C formatter, which lays out the text it is
  given and decides nothing, and the float32 certifier, which generates nothing and reads
  the printed body back on purpose: a regex over generated C (or over labels of the
  model) is not how codegen learns anything.
* The kernels each controller step calls (``kernels.step_calls``, from the declaration and
  the layout) are those its generated C calls: the template's branches and the backend's
  computation agree (read here, in the test, from the committed files).
"""

from __future__ import annotations

import ast
import re
from collections import Counter
from pathlib import Path
from typing import Any

import jinja2
import pytest

from codegen.backends.c.backend import CBackend
from codegen.backends.c.files import TEMPLATE_DIR
from codegen.backends.c.kernels import step_calls
from codegen.controller_api import CONTROLLERS
from codegen.generate import layout_for, robot_target
from modeling.rendering import template_label
from modeling.robot_file import load_robot_model

ROOT = Path(__file__).resolve().parents[2]
# The C formatter wraps and indents the text it is given; it decides no content. The
# float32 certifier (issue 50) generates nothing: it must read the printed body back, in
# the printed operation order, to certify exactly what the C computes (its lexer and its
# input-access reader are regular expressions over that body).
MAY_USE_RE = {"codegen/backends/c/format.py", "codegen/backends/c/certify/program.py",
              "codegen/backends/c/certify/boxes.py"}


def _renders(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """Count every Jinja render of a C template from now on, by template name."""
    counts: Counter[str] = Counter()
    real = jinja2.Template.render

    def counting(self: jinja2.Template, *args: Any, **kwargs: Any) -> str:
        if self.filename and Path(self.filename).parent == TEMPLATE_DIR:
            counts[str(self.name)] += 1
        return real(self, *args, **kwargs)

    monkeypatch.setattr(jinja2.Template, "render", counting)
    return counts


@pytest.fixture(scope="module")
def drishti_target() -> Any:
    model, robot = load_robot_model(None)
    return robot_target(model, robot)


def test_each_c_template_is_rendered_once_per_file_it_writes(
    drishti_target: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    counts = _renders(monkeypatch)
    files = CBackend().render(drishti_target)
    assert counts["controller.c.jinja"] == len(CONTROLLERS)  # (a plain statement of it)
    for name, rendered in sorted(counts.items()):
        line = f"Template: {template_label(TEMPLATE_DIR, name)}\n"
        written = sum(line in text for text in files.values())
        if written:
            assert rendered == written, (name, rendered, written)
        else:  # a fragment spliced into a file: once
            assert rendered <= 1, (name, rendered)


def _uses_re(tree: ast.AST) -> bool:
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name == "re" for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and node.module == "re":
            return True
    return False


def test_codegen_does_not_use_regular_expressions() -> None:
    users = {
        path.relative_to(ROOT).as_posix()
        for path in sorted((ROOT / "codegen").rglob("*.py"))
        if _uses_re(ast.parse(path.read_text(encoding="utf-8")))
    }
    assert users <= MAY_USE_RE, sorted(users - MAY_USE_RE)


@pytest.mark.parametrize("robot", ["drishti", "trailer"])
def test_step_calls_are_the_kernels_the_generated_steps_call(robot: str) -> None:
    model, _ = load_robot_model(None if robot == "drishti"
                                else ROOT / "modeling" / "robots" / robot / f"{robot}.toml")
    layout = layout_for(model)
    folder = ROOT / "generated" / (model.output_dir or ".") / "c"
    kp = f"{layout.prefix}_k_"
    for info in CONTROLLERS:
        text = (folder / f"{layout.prefix}_{info.name}.c").read_text(encoding="utf-8")
        called = set(re.findall(rf"\b{re.escape(kp)}(\w+)\(", text))
        called = {name for name in called if not name.endswith("_keep")}
        assert called == set(step_calls(info, layout)), info.name
