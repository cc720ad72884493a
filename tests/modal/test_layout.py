"""The shape of the modal package: small modules, no import cycle, the command line on top of everything."""
from __future__ import annotations

import ast
import re

from support.paths import ROOT

PACKAGE = ROOT / "modal"
#: the command line: only these (and ``modal/__main__``) may import one another
CLI_MODULES = {"modal.cli", "modal.cli_time", "modal.batch.cli", "modal.__main__"}


def _modules() -> dict[str, tuple]:
    """Every module of modal: dotted name -> (path, is a package's __init__)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def import_graph() -> dict[str, set[str]]:
    """Which modal modules each modal module imports, function-local imports included (``from . import x``
    counts as importing the submodule x, not the package)."""
    modules = _modules()
    graph = {name: set() for name in modules}
    for name, (path, is_package) in modules.items():
        base = name.split(".") if is_package else name.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                parent = ".".join(base[:len(base) - node.level + 1] + ([node.module] if node.module else [])) \
                    if node.level else node.module
                targets = [f"{parent}.{alias.name}" if f"{parent}.{alias.name}" in modules else parent
                           for alias in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:  # the module a dotted name lies in
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycle_inside_modal():
    graph = import_graph()
    assert "modal.sdof.pipeline" in graph and "modal.assemble" in graph["modal.sdof.pipeline"]  # the graph is read
    assert cycles(graph) == []


def test_library_modules_never_import_the_command_line():
    offenders = {name: sorted(imported & CLI_MODULES) for name, imported in import_graph().items()
                 if name not in CLI_MODULES and imported & CLI_MODULES}
    assert offenders == {}


def test_modules_are_small_and_identify_is_a_front_door():
    sizes = {name: len(path.read_text().splitlines()) for name, (path, _) in _modules().items()}
    assert {name: n for name, n in sizes.items() if n > 750} == {}
    assert sizes["modal.identify"] <= 300


def test_no_module_probes_an_frf_for_fields_it_may_not_have():
    # what identification needs is a field of FRF: read, never probed with a default
    probe = re.compile(r"getattr\(\s*(frf|work|estimate)\s*,\s*[\"'][a-z_]+[\"']\s*,")
    found = [f"{path.relative_to(ROOT)}:{n}" for path in PACKAGE.rglob("*.py")
             for n, line in enumerate(path.read_text().splitlines(), 1) if probe.search(line)]
    assert found == []
