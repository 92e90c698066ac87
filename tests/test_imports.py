"""The project's modules import one another without a circle (function-local imports counted too)."""

import ast
import os

from helpers import ROOT

PACKAGES = ("experiments", "imrl_jax")


def imports(path: str, package_modules: set[str]) -> set[str]:
    """The project's modules a file imports anywhere in it (``from experiments import x`` counts x if a module)."""
    found = set()
    with open(path) as f:
        tree = ast.parse(f.read())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] in PACKAGES:
            if node.module in PACKAGES:
                found |= {f"{node.module}.{a.name}" for a in node.names} & package_modules
            else:
                found.add(node.module)
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] in PACKAGES}
    return found & package_modules


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_module_imports_itself_through_others():
    files = {f"{p}.{name[:-3]}": os.path.join(ROOT, p, name) for p in PACKAGES
             for name in os.listdir(os.path.join(ROOT, p)) if name.endswith(".py")}
    graph = {module: imports(path, set(files)) - {module} for module, path in files.items()}
    assert circles(graph) == []
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]  # the check can fail
