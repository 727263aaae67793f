"""The import structure: no import cycle anywhere, and the one-way rule of DESIGN.md.

Every Python file of ``modeling/``, ``codegen/``, ``runtime/`` and ``generated/`` is parsed
with ``ast`` (nothing is imported). An import is an edge of the module graph wherever it
is written: at module level (run when the module is imported) and inside a function (run
when the function is called) alike, because a function-local import that closes a circle
is a circle all the same, only hidden. Relative imports are resolved; ``from p import x``
is an edge to the module ``p.x`` when that module exists, else to ``p``; a call
``importlib.import_module("a.b")`` with a literal name is an edge too. Imports under
``if TYPE_CHECKING:`` are left out (they never run). Importing ``a.b.c`` also runs the
``__init__`` of ``a`` and ``a.b``; those implicit edges are left out (as import-linter
does), or a package whose ``__init__`` re-exports its submodules would be a cycle with each
of them.

The rules (:func:`rule_broken`; each failure names the file, the line and the rule):

* no cycle among the project's modules;
* ``modeling/`` imports none of ``codegen/``, ``runtime/``, ``generated/``;
* ``codegen/`` imports neither ``runtime/`` nor ``generated/``; a backend
  (``codegen/backends/<name>/``) imports no other backend, and the rest of ``codegen/``
  imports none (the registry ``codegen.backends`` finds them by name);
* ``generated/`` imports none of the project's packages, and not SymPy (NumPy-only code);
* ``runtime/`` outside ``runtime/tooling/`` imports neither ``runtime/tooling/``, nor
  ``codegen/``, nor SymPy, anywhere. Of ``modeling/`` it imports only the modules of
  ``RUNTIME_MODELING`` (and from ``modeling.robot_file`` only ``load_robot``), which import
  no SymPy at module level: only the standard library, Jinja2 and each other. The one road
  from the runtime to SymPy is ``load_robot`` of a ``[physical]`` file, whose lumped
  parameters follow from Drishti's derived lumped relations (imported inside that
  function: a ``[lumped]`` file is read without SymPy). The import-time closure of every
  runtime module (module-level edges, followed transitively through every package)
  contains neither SymPy nor ``codegen/`` nor ``runtime/tooling/``.

* ``runtime/`` is built on floors (:data:`RUNTIME_FLOORS`, from the bottom): each of its
  sub-packages and top-level modules imports only from itself and from the floors below,
  anywhere (a function-local import included: an upward import deferred into a function is
  a cycle waiting to close); the sub-packages and modules of one floor import none of each
  other. So no two of them import each other (:func:`mutual_pairs`), and none needs a
  function-local import to dodge a circle. Only the command line (:data:`COMMAND_LINE`:
  ``commands``, ``cli``, ``tooling``) imports ``argparse``: every ``main`` is a command's.
  ``runtime/tooling/`` (witness, fuzz driver, bench, firmware) is the top floor: it may
  import anything below it.

``runtime.cli`` names the commands' modules (``runtime.commands.*``) as strings and imports
the one a command runs: such a name is not an edge.
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("modeling", "codegen", "runtime", "generated")

# What runtime/ outside tooling/ may import from modeling/: module -> the names it may take
# (None: any). Importing one of these imports no SymPy: only the standard library, the
# packages of RUNTIME_MODELING_NEEDS and other modeling modules that import no more
# (checked below).
RUNTIME_MODELING: dict[str, frozenset[str] | None] = {
    "modeling.version": None,  # VERSION
    "modeling.package_paths": None,  # where generated/ and the build cache are
    "modeling.robot_io": None,  # robot files as files: errors, text, digest, which format
    "modeling.rendering": None,  # the strict Jinja2 environment (wmr freeze's header)
    "modeling.planar_robot": None,  # a robot's layout in numbers (the MuJoCo plant)
    "modeling.mjcf_export": None,  # its MJCF (the MuJoCo plant)
    "modeling.contact_loads": None,  # the one load model (slip monitor, traction limit)
    "modeling.audit": None,  # the physics audit's warnings, printed once as `wmr model` does
    # A robot file's numbers; [physical] → lumped is the one run-time use of SymPy here.
    # Not load_robot_model: that derives a model (SymPy), which is codegen's job.
    "modeling.robot_file": frozenset({"load_robot"}),
}

RUNTIME_MODELING_NEEDS = frozenset({"jinja2", "numpy"})

# The floors of runtime/, from the bottom: its sub-packages (runtime/<name>/) and top-level
# modules (runtime/<name>.py). A module imports only from its own and from lower floors;
# those sharing a floor import none of each other. Every one is listed (a new one is put on
# its floor here).
RUNTIME_FLOORS: tuple[tuple[str, ...], ...] = (
    ("runtime",),  # the package's __init__ (no code)
    ("experiment",),  # experiment data: settings, faults
    ("bindings",),  # the generated code built, loaded, configured; --robot resolved
    ("setting",),  # a robot and its experiment scaled to it: scale, layout, the run setting
    ("sim",),  # the one closed loop (no check), the generated-model plant
    ("mujoco",),  # the other plants
    ("plants",),  # the plant registry, above every plant
    ("stability",),  # verdicts and the configuration checks (no main)
    ("reproduction", "fault_table", "plant_comparison"),  # the drivers
    ("paper", "campaign", "freeze"),  # reports, campaigns, frozen configurations
    ("commands",),  # every main and argparse parser
    ("cli",),  # wmr: names the commands as strings
    ("__main__",),  # python -m runtime
    ("tooling",),  # witness, fuzz driver, bench, firmware: above everything
)

# The entries that parse a command line (argparse): every command's main is in commands/.
COMMAND_LINE = frozenset({"commands", "cli", "__main__", "tooling"})

# Violations being removed on another branch (each with the reason). The test fails when an
# entry no longer occurs, so that the list only shrinks.
ALLOWED: dict[tuple[str, str], str] = {}


@dataclass(frozen=True)
class Import:
    """One import statement's edge: ``source`` imports ``target`` at ``line``."""

    source: str
    target: str  # a project module, or the top-level name of another package
    names: tuple[str, ...]  # the names of ``from target import ...`` ("" for a module)
    line: int
    local: bool  # inside a function: runs when it is called, not at import time

    @property
    def where(self) -> str:
        return f"{module_files()[self.source].relative_to(ROOT)}:{self.line}"


@cache
def module_files() -> dict[str, Path]:
    """Every project module (dotted name) and its file."""
    found: dict[str, Path] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join(parts)] = path
    return found


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _resolve(module: str, level: int, name: str | None) -> str:
    """The absolute module of ``from <level dots><name> import ...`` written in ``module``."""
    if level == 0:
        assert name is not None
        return name
    is_package = module_files()[module].name == "__init__.py"
    parts = module.split(".") if is_package else module.split(".")[:-1]
    base = parts[: len(parts) - (level - 1)]
    return ".".join([*base, name] if name else base)


def _target(dotted: str) -> str:
    """A project module (the longest existing prefix) or another package's top-level name."""
    modules = module_files()
    parts = dotted.split(".")
    if parts[0] not in PACKAGES:
        return parts[0]
    for n in range(len(parts), 0, -1):
        candidate = ".".join(parts[:n])
        if candidate in modules:
            return candidate
    return dotted


def _walk(node: ast.AST, local: bool) -> Iterator[tuple[ast.AST, bool]]:
    """Every node under ``node`` with whether it runs inside a function, skipping the bodies
    of ``if TYPE_CHECKING:``."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            for other in child.orelse:
                yield other, local
                yield from _walk(other, local)
            continue
        inner = local or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
        yield child, inner
        yield from _walk(child, inner)


@cache
def imports_of(module: str) -> tuple[Import, ...]:
    """The edges of one module (see the module docstring for what counts)."""
    modules = module_files()
    tree = ast.parse(modules[module].read_text(encoding="utf-8"))
    out: list[Import] = []
    for node, local in _walk(tree, False):
        if isinstance(node, ast.Import):
            out += [Import(module, _target(a.name), (), node.lineno, local) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = _resolve(module, node.level, node.module)
            by_target: dict[str, list[str]] = {}
            for a in node.names:
                sub = f"{base}.{a.name}"
                target = sub if sub in modules else _target(base)
                by_target.setdefault(target, []).append("" if target == sub else a.name)
            out += [Import(module, t, tuple(n), node.lineno, local) for t, n in by_target.items()]
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute | ast.Name)
            and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
            and not node.args[0].value.startswith(".")
        ):
            out.append(Import(module, _target(node.args[0].value), (), node.lineno, local))
    return tuple(i for i in out if i.target != module)


def all_imports() -> list[Import]:
    return [i for m in module_files() for i in imports_of(m)]


def internal_graph(module_level_only: bool = False) -> dict[str, set[str]]:
    """Project module -> the project modules it imports."""
    modules = module_files()
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for i in all_imports():
        if i.target in modules and not (module_level_only and i.local):
            graph[i.source].add(i.target)
    return graph


def components(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module: the modules on a common
    cycle (Tarjan's algorithm, iterative; sorted by their smallest module)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = set()
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.add(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(component)
    return sorted(found, key=min)


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One shortest cycle (a → … → a) through each of :func:`components`."""
    return [_cycle_in(graph, c) for c in components(graph)]


def _cycle_in(graph: dict[str, set[str]], component: set[str]) -> list[str]:
    """A shortest cycle through the smallest module of a strongly connected component."""
    start = min(component)
    paths = {start: [start]}
    frontier = [start]
    while frontier:
        following: list[str] = []
        for node in frontier:
            for child in sorted(graph[node] & component):
                if child == start:
                    return [*paths[node], start]
                if child not in paths:
                    paths[child] = [*paths[node], child]
                    following.append(child)
        frontier = following
    raise AssertionError(f"no cycle through {start}")  # pragma: no cover


def layer(module: str) -> str:
    """``modeling``, ``codegen``, ``runtime.tooling``, ``runtime``, ``generated`` or, for
    another package, its name."""
    if module.startswith("runtime.tooling"):
        return "runtime.tooling"
    return module.split(".")[0]


def _backend(module: str) -> str | None:
    """The backend package a codegen module belongs to (``codegen.backends.c``), if any."""
    parts = module.split(".")
    return ".".join(parts[:3]) if parts[:2] == ["codegen", "backends"] and len(parts) > 2 else None


def rule_broken(i: Import) -> str | None:
    """Which rule of the module docstring an import breaks, or None."""
    src, dst = layer(i.source), layer(i.target)
    if src == "modeling" and dst in ("codegen", "runtime", "runtime.tooling", "generated"):
        return f"modeling/ imports {dst}/"
    if src == "codegen":
        if dst in ("runtime", "runtime.tooling", "generated"):
            return f"codegen/ imports {dst}/"
        mine, theirs = _backend(i.source), _backend(i.target)
        if theirs is not None and mine != theirs:
            return (f"{mine or 'codegen outside the backends'} imports the backend {theirs} "
                    "(the registry codegen.backends finds backends by name)")
    if src == "generated" and dst != "generated" and (dst in PACKAGES or dst == "sympy"):
        return f"generated/ imports {dst} (generated code is NumPy-only and standalone)"
    if src == "runtime":
        if dst in ("runtime.tooling", "codegen", "sympy"):
            return f"runtime/ outside tooling/ imports {dst}"
        if dst == "modeling":
            if i.target not in RUNTIME_MODELING:
                return (f"runtime/ outside tooling/ imports {i.target}; it may import only "
                        f"{', '.join(RUNTIME_MODELING)}")
            allowed = RUNTIME_MODELING[i.target]
            extra = [n for n in i.names if allowed is not None and n not in allowed]
            if extra or (allowed is not None and not i.names):
                return (f"runtime/ outside tooling/ imports {extra or 'the module'} from "
                        f"{i.target}; only {', '.join(sorted(allowed or ()))}")
    return None


def runtime_unit(module: str) -> str | None:
    """The floor entry a module belongs to: its runtime sub-package or top-level module
    (``runtime.sim.loop`` → ``sim``, ``runtime.cli`` → ``cli``, ``runtime`` → ``runtime``),
    None outside runtime/."""
    parts = module.split(".")
    if parts[0] != "runtime":
        return None
    return parts[1] if len(parts) > 1 else "runtime"


def floor_of(unit: str, floors: tuple[tuple[str, ...], ...] = RUNTIME_FLOORS) -> int:
    return next(n for n, floor in enumerate(floors) if unit in floor)


def floor_broken(i: Import, floors: tuple[tuple[str, ...], ...] = RUNTIME_FLOORS
                 ) -> str | None:
    """Which floor rule an import breaks (an import upwards, or between two entries of one
    floor; argparse below the command line), or None."""
    src, dst = runtime_unit(i.source), runtime_unit(i.target)
    if i.target == "argparse" and src is not None and src not in COMMAND_LINE:
        return (f"runtime.{src} imports argparse: a command's parser and main belong to "
                "runtime.commands")
    if src is None or dst is None or src == dst:
        return None
    up, down = floor_of(src, floors), floor_of(dst, floors)
    if down > up:
        return (f"runtime.{src} (floor {up}) imports runtime.{dst}, a floor above it "
                f"({down})")
    if down == up:
        return f"runtime.{src} imports runtime.{dst}, on its own floor ({up})"
    return None


def mutual_pairs(imports: list[Import]) -> list[tuple[str, str]]:
    """The pairs of runtime sub-packages or top-level modules that import each other
    (function-local imports included)."""
    edges = {(a, b) for i in imports
             if (a := runtime_unit(i.source)) and (b := runtime_unit(i.target)) and a != b}
    return sorted((a, b) for a, b in edges if a < b and (b, a) in edges)


def violations() -> list[tuple[Import, str]]:
    return [(i, r) for i in all_imports() if (r := rule_broken(i)) is not None]


def import_time_closure(module: str) -> set[str]:
    """Every module (project or other package) that importing ``module`` imports."""
    graph = internal_graph(module_level_only=True)
    seen: set[str] = set()
    todo = [module]
    external: set[str] = set()
    while todo:
        node = todo.pop()
        if node in seen:
            continue
        seen.add(node)
        external |= {i.target for i in imports_of(node)
                     if not i.local and i.target not in graph}
        todo += sorted(graph[node] - seen)
    return (seen - {module}) | external


# ---------------------------------------------------------------------------------------
def test_the_scan_sees_every_package_and_both_kinds_of_import() -> None:
    """A scan that found nothing would pass every rule: it sees each package, function-
    local imports and relative ones, and leaves TYPE_CHECKING blocks out."""
    modules = module_files()
    for package in PACKAGES:
        assert any(m.split(".")[0] == package for m in modules), package
    assert "generated.python.controllers" in modules
    found = all_imports()
    assert any(i.local for i in found) and any(not i.local for i in found)
    # generated/python/controllers.py: `from . import wmr_laws as laws`
    assert any(i.source == "generated.python.controllers"
               and i.target == "generated.python.wmr_laws" for i in found)
    # runtime/bindings/generated.py imports generated.python only under TYPE_CHECKING
    # (and by importlib with a computed name): no edge at import time.
    assert not any(i.source == "runtime.bindings.generated" and i.target.startswith(
        "generated.python.") and not i.local for i in found)


def test_the_checker_finds_a_planted_cycle_and_a_planted_violation() -> None:
    """The cycle finder and the rules on made-up inputs: a checker that cannot fail proves
    nothing."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e2"}, "e2": {"e"}}
    assert cycles(graph) == [["a", "b", "c", "a"], ["e", "e2", "e"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
    planted = Import("modeling.lagrange", "codegen.template_util", (), 1, True)
    assert rule_broken(planted) == "modeling/ imports codegen/"
    assert rule_broken(Import("runtime.bindings.cbuild", "sympy", (), 1, True)) is not None
    assert rule_broken(Import("runtime.bindings.cbuild", "modeling.robot_file",
                              ("load_robot_model",), 1, True)) is not None
    assert rule_broken(Import("runtime.tooling.bench.report", "sympy", (), 1, False)) is None


def test_every_runtime_package_is_on_one_floor() -> None:
    units = {u for m in module_files() if (u := runtime_unit(m)) is not None}
    declared = [u for floor in RUNTIME_FLOORS for u in floor]
    assert len(declared) == len(set(declared)), "an entry is on two floors"
    assert units == set(declared), (f"not on a floor: {sorted(units - set(declared))}; "
                                    f"no such package: {sorted(set(declared) - units)}")
    assert RUNTIME_FLOORS[-1] == ("tooling",)  # tooling stays above everything


def test_runtime_imports_only_the_floors_below() -> None:
    broken = [(i, r) for i in all_imports() if (r := floor_broken(i)) is not None]
    assert not broken, "imports against runtime/'s floors (RUNTIME_FLOORS):\n" + "\n".join(
        f"{i.where}: {i.source} imports {i.target}"
        f"{' (inside a function)' if i.local else ''}: {r}" for i, r in broken
    )
    assert mutual_pairs(all_imports()) == []


def test_the_floor_rule_fails_on_a_planted_upward_import() -> None:
    """The floor rule and the pair finder on made-up imports: an upward import (at module
    level or inside a function), one between two entries of a floor, and a mutual pair are
    found; a downward one is not."""
    up = Import("runtime.sim.loop", "runtime.stability.checks", (), 149, True)
    assert floor_broken(up) == ("runtime.sim (floor 4) imports runtime.stability, a floor "
                                "above it (7)")
    assert floor_broken(Import("runtime.experiment.settings", "runtime.sim.faults", (), 33,
                               False)) is not None
    assert floor_broken(Import("runtime.paper.figures", "runtime.campaign.store", (), 1,
                               False)) == ("runtime.paper imports runtime.campaign, on its own "
                                           "floor (9)")
    assert floor_broken(Import("runtime.tooling.bench.report", "runtime.cli", (), 1,
                               False)) is None
    assert floor_broken(Import("runtime.stability.checks", "runtime.sim.loop", (), 1,
                               False)) is None
    assert floor_broken(Import("runtime.sim.loop", "runtime.sim.plant", (), 1, False)) is None
    assert floor_broken(Import("runtime.stability.analysis", "argparse", (), 15, False))
    assert floor_broken(Import("runtime.commands.stability", "argparse", (), 8, False)) is None
    planted = [*all_imports(), up]
    assert mutual_pairs(planted) == [("sim", "stability")]
    broken = [i for i in planted if floor_broken(i) is not None]
    assert broken == [up]


def test_no_import_cycle() -> None:
    graph = internal_graph()
    found = components(graph)
    assert not found, "import cycles (function-local imports included):\n" + "\n".join(
        f"{' -> '.join(_cycle_in(graph, c))}  (the {len(c)} modules on a cycle: "
        f"{', '.join(sorted(c))})" for c in found
    )


def test_the_one_way_rule() -> None:
    broken = [(i, r) for i, r in violations() if (i.source, i.target) not in ALLOWED]
    assert not broken, "imports against DESIGN.md's one-way rule:\n" + "\n".join(
        f"{i.where}: {i.source} imports {i.target}"
        f"{' (inside a function)' if i.local else ''}: {r}" for i, r in broken
    )


def test_the_allow_list_only_holds_live_violations() -> None:
    live = {(i.source, i.target) for i, _ in violations()}
    stale = [f"{s} -> {t}" for s, t in ALLOWED if (s, t) not in live]
    assert not stale, f"fixed, remove from ALLOWED: {stale}"


def test_runtime_modeling_modules_are_light_at_import() -> None:
    """The modeling modules the runtime may import pull in nothing but the standard library,
    Jinja2 and other such modeling modules when imported (SymPy only inside the functions
    that need it)."""
    for module in RUNTIME_MODELING:
        assert module in module_files(), f"{module} does not exist: update RUNTIME_MODELING"
        closure = import_time_closure(module)
        heavy = sorted(m for m in closure if layer(m) in PACKAGES and layer(m) != "modeling")
        heavy += sorted(m for m in closure if layer(m) not in PACKAGES
                        and m not in sys.stdlib_module_names and m != "__future__"
                        and m not in RUNTIME_MODELING_NEEDS)
        assert not heavy, f"importing {module} imports {heavy}"


@pytest.mark.parametrize(
    "module", sorted(m for m in module_files() if layer(m) == "runtime")
)
def test_importing_runtime_imports_no_sympy_or_codegen(module: str) -> None:
    closure = import_time_closure(module)
    bad = sorted(m for m in closure if m == "sympy" or layer(m) in ("codegen",
                                                                     "runtime.tooling"))
    assert not bad, f"importing {module} imports {bad}"
