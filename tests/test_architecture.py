"""The shape of the code, read from the source with ``ast``: dependencies point one way, no
import cycles, no private names across modules, one name per concept (no class name defined
twice), a request per command, a module per concept, docstrings on the public API.

Every import counts, lazy ones inside functions included: a lazy import hides a cycle from
Python, not from the design.
"""

from __future__ import annotations

import ast
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("replay", "recorder", "processors", "rerun_export", "camlog")
#: package -> the packages it must not import (recorder -> replay <- processors, replay <-
#: rerun_export; camlog: all)
FORBIDDEN = {
    "replay": {"recorder", "processors", "rerun_export", "camlog"},
    "recorder": {"processors", "rerun_export", "camlog"},
    "processors": {"recorder", "rerun_export", "camlog"},
    "rerun_export": {"recorder", "processors", "camlog"},
    "camlog": set(),
}
#: a module holds one concept; past this many lines it holds two (split it by concept, never
#: to get under a count: a concept this long stays whole)
MAX_LINES = 600
#: the most positional parameters a public function or method takes: the others are
#: keyword-only, named at every call (rather than packed into a wrapper the callee unpacks)
MAX_POSITIONAL = 5


@dataclass
class Import:
    """One imported module: the names taken from it, the line, and local aliases of it."""

    target: str
    names: list[str]
    line: int


@dataclass
class Module:
    """One source module: its dotted name, where it is, its syntax tree and its imports."""

    name: str
    where: str
    tree: ast.Module
    is_package: bool
    lines: int
    imports: list[Import] = field(default_factory=list)
    aliases: dict[str, str] = field(default_factory=dict)  # local name -> module it binds

    @property
    def package(self) -> str:
        """The dotted name relative imports start from."""
        return self.name if self.is_package else self.name.rpartition(".")[0]


def _resolve(modules: dict[str, Module]) -> dict[str, Module]:
    """Fill every module's imports and module aliases."""
    for module in modules.values():
        for node in ast.walk(module.tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    module.imports.append(Import(alias.name, [], node.lineno))
                    if alias.asname:
                        module.aliases[alias.asname] = alias.name
            elif isinstance(node, ast.ImportFrom):
                target = node.module or ""
                if node.level:
                    base = module.package.split(".")
                    base = base[: len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                rest = []
                for alias in node.names:
                    if f"{target}.{alias.name}" in modules:  # a submodule
                        module.imports.append(Import(f"{target}.{alias.name}", [], node.lineno))
                        module.aliases[alias.asname or alias.name] = f"{target}.{alias.name}"
                    else:
                        rest.append(alias.name)
                if rest:
                    module.imports.append(Import(target, rest, node.lineno))
    return modules


def _read_tree() -> dict[str, Module]:
    found: dict[str, Module] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            if is_package:
                parts.pop()
            text = path.read_text()
            found[".".join(parts)] = Module(".".join(parts), str(path.relative_to(ROOT)),
                                            ast.parse(text, str(path)), is_package,
                                            len(text.splitlines()))
    return _resolve(found)


@pytest.fixture(scope="module")
def modules() -> dict[str, Module]:
    """Every module of the packages, read once by the worker that runs these tests (not by
    every worker at collection)."""
    return _read_tree()


def _top(name: str) -> str:
    return name.split(".", maxsplit=1)[0]


def wrong_direction(modules: dict[str, Module]) -> list[str]:
    """Imports that go against the dependency direction."""
    return [f"{m.where}:{i.line} imports {i.target}" for m in modules.values()
            for i in m.imports if _top(i.target) in FORBIDDEN.get(_top(m.name), set())]


def cycles(modules: dict[str, Module]) -> list[list[str]]:
    """Groups of modules that import each other, directly or around a loop (Tarjan's
    strongly connected components)."""
    graph = {name: sorted({i.target for i in m.imports if i.target in modules
                           and i.target != name}) for name, m in modules.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in graph[node]:
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = stack[stack.index(node):]
            del stack[stack.index(node):]
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_uses(modules: dict[str, Module]) -> list[str]:
    """``_private`` names of one module imported or used as attributes by another."""
    wrong = [f"{m.where}:{i.line} imports {i.target}.{name}" for m in modules.values()
             for i in m.imports if _top(i.target) in PACKAGES and i.target != m.name
             for name in i.names if _private(name)]
    for m in modules.values():
        for node in ast.walk(m.tree):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and \
                    node.value.id in m.aliases and _private(node.attr):
                wrong.append(f"{m.where}:{node.lineno} uses {m.aliases[node.value.id]}."
                             f"{node.attr}")
    return wrong


#: the command modules' protocol (camlog.cli.COMMANDS): every one defines these functions
COMMAND_PROTOCOL = {"add_arguments", "run"}


def twins(modules: dict[str, Module]) -> dict[str, list[str]]:
    """Names given to two things: every class name, and every public module-level function
    name (but the command modules' protocol), defined in more than one place, with where."""
    places: dict[str, list[str]] = {}
    for module in modules.values():
        for node in ast.walk(module.tree):
            if isinstance(node, ast.ClassDef):
                places.setdefault(node.name, []).append(f"{module.where}:{node.lineno}")
        for node in module.tree.body:
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and \
                    not node.name.startswith("_") and not (
                        module.name.startswith("camlog.cli.") and node.name in COMMAND_PROTOCOL):
                places.setdefault(f"{node.name}()", []).append(f"{module.where}:{node.lineno}")
    return {name: where for name, where in places.items() if len(where) > 1}


def _classes(modules: dict[str, Module]) -> dict[str, list[ast.ClassDef]]:
    classes: dict[str, list[ast.ClassDef]] = {}
    for module in modules.values():
        for node in ast.walk(module.tree):
            if isinstance(node, ast.ClassDef):
                classes.setdefault(node.name, []).append(node)
    return classes


def _inherited(node: ast.ClassDef, classes: dict[str, list[ast.ClassDef]],
               seen: frozenset[str] = frozenset()) -> set[str]:
    """Method names the class's bases (in this tree) define: an override shares their
    docstring, as ``inspect.getdoc`` reads it."""
    names: set[str] = set()
    for base in node.bases:
        name = base.id if isinstance(base, ast.Name) else \
            base.attr if isinstance(base, ast.Attribute) else ""
        for parent in classes.get(name, []):
            if parent.name not in seen:
                names |= {item.name for item in parent.body
                          if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef)}
                names |= _inherited(parent, classes, seen | {parent.name})
    return names


def undocumented(modules: dict[str, Module]) -> Iterator[str]:
    """Public module-level functions and classes, and public methods of public classes,
    without a docstring."""
    classes = _classes(modules)
    defs = ast.FunctionDef | ast.AsyncFunctionDef
    for module in modules.values():
        for node in module.tree.body:
            if not isinstance(node, defs | ast.ClassDef) or node.name.startswith("_"):
                continue
            if ast.get_docstring(node) is None:
                yield f"{module.where}:{node.lineno} {node.name}"
            if isinstance(node, ast.ClassDef):
                inherited = _inherited(node, classes)
                yield from (f"{module.where}:{item.lineno} {node.name}.{item.name}"
                            for item in node.body
                            if isinstance(item, defs) and not item.name.startswith("_")
                            and item.name not in inherited and ast.get_docstring(item) is None)


def _parameters(node: ast.FunctionDef | ast.AsyncFunctionDef, *, method: bool) -> int:
    """Positional parameters and ``*args`` (a method's first, ``self`` or ``cls``, not
    counted)."""
    args = node.args
    count = len(args.posonlyargs) + len(args.args) + (args.vararg is not None)
    static = any(isinstance(d, ast.Name) and d.id == "staticmethod"
                 for d in node.decorator_list)
    return count - 1 if method and not static and (args.posonlyargs or args.args) else count


def crowded(modules: dict[str, Module]) -> list[str]:
    """Public module-level functions, and public methods of public classes, with more than
    :data:`MAX_POSITIONAL` positional parameters."""
    defs = ast.FunctionDef | ast.AsyncFunctionDef
    found = []
    for module in modules.values():
        for node in module.tree.body:
            if not isinstance(node, defs | ast.ClassDef) or node.name.startswith("_"):
                continue
            if isinstance(node, defs):
                n = _parameters(node, method=False)
                if n > MAX_POSITIONAL:
                    found.append(f"{module.where}:{node.lineno} {node.name} ({n})")
            else:
                for item in node.body:
                    if isinstance(item, defs) and not item.name.startswith("_"):
                        n = _parameters(item, method=True)
                        if n > MAX_POSITIONAL:
                            found.append(f"{module.where}:{item.lineno} {node.name}."
                                         f"{item.name} ({n})")
    return found


def command_requests(modules: dict[str, Module], commands: dict[str, str]) -> dict[str, str]:
    """Command -> how it breaks the rule "a command is one request": its module's
    ``add_arguments`` is ``add_request(p, SomeRequest)`` with a request of
    :mod:`camlog.requests`, and its ``run`` builds that request once, with
    ``request_from_args``."""
    wrong = {}
    for command, module_name in commands.items():
        module = modules[f"camlog.cli.{module_name}"]
        functions = {n.name: n for n in module.tree.body if isinstance(n, ast.FunctionDef)}
        body = [s for s in functions["add_arguments"].body
                if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))]
        call = body[0].value if len(body) == 1 and isinstance(body[0], ast.Expr) else None
        request = call.args[1] if isinstance(call, ast.Call) and isinstance(
            call.func, ast.Name) and call.func.id == "add_request" and len(call.args) == 2 \
            else None
        source = next((i.target for i in module.imports if isinstance(request, ast.Name)
                       and request.id in i.names), "")
        if not isinstance(request, ast.Name) or not source.startswith("camlog.requests."):
            wrong[command] = "add_arguments is not add_request(p, <a camlog.requests request>)"
            continue
        built = [n for n in ast.walk(functions["run"]) if isinstance(n, ast.Call)
                 and isinstance(n.func, ast.Name) and n.func.id == "request_from_args"
                 and len(n.args) == 2 and isinstance(n.args[0], ast.Name)
                 and n.args[0].id == request.id]
        if len(built) != 1:
            wrong[command] = f"run does not build its {request.id} once"
    return wrong


def _sample(**sources: str) -> dict[str, Module]:
    """Modules made from source text, named by their keyword (``a__b`` is ``a.b``)."""
    modules = {}
    for key, text in sources.items():
        name = key.replace("__", ".")
        source = textwrap.dedent(text)
        modules[name] = Module(name, name, ast.parse(source), False, len(source.splitlines()))
    return _resolve(modules)


def test_the_checks_find_what_they_look_for() -> None:
    sample = _sample(
        replay__a="from replay import b\n",
        replay__b="from . import a\nimport replay.a as x\nx._hidden()\n",
        replay__d="from camlog.c import run\n",
        camlog__c="from replay.a import _secret\n\ndef run():\n    pass\n\nclass K:\n"
                  "    '''Documented.'''\n    def go(self):\n        pass\n",
    )
    assert wrong_direction(sample) == ["replay.d:1 imports camlog.c"]
    assert cycles(sample) == [["replay.a", "replay.b"]]
    assert private_uses(sample) == ["camlog.c:1 imports replay.a._secret",
                                    "replay.b:3 uses replay.a._hidden"]
    assert list(undocumented(sample)) == ["camlog.c:3 run", "camlog.c:8 K.go"]
    many = _sample(
        camlog__m="def wide(a, b, c, d, e, f, g, *, h, i):\n    pass\n\n"
                  "def fine(a, b, c, d, *e, f, g, h, **i):\n    pass\n\n"
                  "def _hidden(a, b, c, d, e, f, g, h, i):\n    pass\n\n"
                  "class K:\n    def go(self, a, b, c, d, e, *, f, g, h):\n        pass\n\n"
                  "    def far(self, a, b, c, d, e, f, g, h, *, i):\n        pass\n",
    )
    assert crowded(many) == ["camlog.m:1 wide (7)", "camlog.m:14 K.far (8)"]
    named = _sample(
        replay__a="class Frame:\n    pass\n\ndef load():\n    pass\n\ndef _own():\n    pass\n",
        camlog__b="def f():\n    class Frame:\n        pass\n\ndef load():\n    pass\n\n"
                  "def _own():\n    pass\n",
        camlog__cli__c="def run():\n    pass\n",
        camlog__cli__d="def run():\n    pass\n",
    )
    assert twins(named) == {"Frame": ["replay.a:1", "camlog.b:2"],
                            "load()": ["replay.a:4", "camlog.b:5"]}
    cli = _sample(
        camlog__requests__r="class GoRequest:\n    pass\n",
        camlog__cli__good="from camlog.requests.r import GoRequest\n\n"
                          "def add_arguments(p):\n    'Doc.'\n    add_request(p, GoRequest)\n\n"
                          "def run(args):\n    go(request_from_args(GoRequest, args))\n",
        camlog__cli__flags="def add_arguments(p):\n    p.add_argument('--x')\n\n"
                           "def run(args):\n    pass\n",
        camlog__cli__twice="from camlog.requests.r import GoRequest\n\n"
                           "def add_arguments(p):\n    add_request(p, GoRequest)\n\n"
                           "def run(args):\n    request_from_args(GoRequest, args)\n"
                           "    request_from_args(GoRequest, args)\n",
    )
    assert command_requests(cli, {"go": "good", "x": "flags", "y": "twice"}) == {
        "x": "add_arguments is not add_request(p, <a camlog.requests request>)",
        "y": "run does not build its GoRequest once"}


def test_the_source_tree_is_read(modules: dict[str, Module]) -> None:
    assert {"replay.formats.base", "camlog.cli", "processors.registry",
            "recorder.record"} <= set(modules)
    assert sum(len(m.imports) for m in modules.values()) > 300


def test_dependencies_point_one_way(modules: dict[str, Module]) -> None:
    assert wrong_direction(modules) == []


def test_no_import_cycles(modules: dict[str, Module]) -> None:
    assert cycles(modules) == []


def test_no_private_names_across_modules(modules: dict[str, Module]) -> None:
    assert private_uses(modules) == []


def test_one_name_per_concept(modules: dict[str, Module]) -> None:
    assert twins(modules) == {}


def test_public_functions_take_few_positional_parameters(modules: dict[str, Module]) -> None:
    assert crowded(modules) == []


def test_every_command_is_one_request(modules: dict[str, Module]) -> None:
    from camlog.cli import COMMANDS

    assert command_requests(modules, {c: m for c, (_, m) in COMMANDS.items()}) == {}


def test_a_module_holds_one_concept(modules: dict[str, Module]) -> None:
    assert {m.where: m.lines for m in modules.values() if m.lines > MAX_LINES} == {}


@pytest.mark.parametrize("package", PACKAGES)
def test_public_functions_and_classes_say_what_they_are_for(package: str,
                                                           modules: dict[str, Module]) -> None:
    mine = {name: m for name, m in modules.items() if _top(name) == package}
    assert [line for line in undocumented(modules) if line.startswith(f"{package}/")] == []
    assert mine
