"""The project's layers (imrl_jax/__init__.py): each module imports only its own layer and those below, without a
circle (function-local imports counted too), and never a command by its short name."""

import ast
import os
import subprocess
import sys

from helpers import ROOT

PACKAGES = ("experiments", "imrl_jax")

#: Each layer's rank: a module may import a module of its rank or lower. The first name that matches a module's
#: dotted name (most specific first) gives its rank.
LAYERS = (
    ("imrl_jax.world", 1), ("imrl_jax.agent", 2), ("imrl_jax.evolution", 3), ("imrl_jax.analysis", 4),
    ("imrl_jax.runs", 5), ("imrl_jax.commands", 6), ("imrl_jax", 0),  # config, conditions, genome, files
    ("experiments.harness", 7), ("experiments", 8),
)
#: The experiments package itself: its ``__init__`` holds no code, and the harness walks it to find the studies.
ROOTS = {"experiments": 7}
#: Imports across the layers' order, each for its reason.
EXCEPTIONS = {
    # gpu_check's ``study`` step times the claims map's programs: it reads the study's table, lazily.
    ("imrl_jax.commands.gpu_study", "experiments.claims_study"),
    ("imrl_jax.commands.gpu_study", "experiments.harness.table"),
    ("imrl_jax.commands.gpu_study", "experiments.harness.reproduce"),
}
#: The longest module, in lines (docs/TESTING.md): one concept a module.
MAX_LINES = 550


def rank(module: str) -> int:
    """The layer of a module by its dotted name."""
    if module in ROOTS:
        return ROOTS[module]
    return next(r for prefix, r in LAYERS if module == prefix or module.startswith(prefix + "."))


def project_files() -> dict[str, str]:
    """Every module of the project by dotted name (a package by its ``__init__``) -> its path."""
    found = {}
    for package in PACKAGES:
        for folder, dirs, names in os.walk(os.path.join(ROOT, package)):
            dirs[:] = [d for d in dirs if os.path.exists(os.path.join(folder, d, "__init__.py"))]
            dotted = os.path.relpath(folder, ROOT).replace(os.sep, ".")
            for name in names:
                if name.endswith(".py"):
                    found[dotted if name == "__init__.py" else f"{dotted}.{name[:-3]}"] = os.path.join(folder, name)
    return found


def imports(path: str, modules: set[str]) -> set[str]:
    """The project's modules a file imports anywhere in it (``from imrl_jax.agent import x`` counts x, a module).

    Raises AssertionError at a name of the project that is no module nor an attribute of one's package
    (``imrl_jax.evolve``: a command by its short name, which only ``python -m`` may use)."""
    found = set()
    with open(path) as f:
        tree = ast.parse(f.read())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] in PACKAGES:
            assert node.module in modules, f"{path}:{node.lineno}: no module {node.module}"
            for alias in node.names:
                found.add(f"{node.module}.{alias.name}" if f"{node.module}.{alias.name}" in modules else node.module)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] in PACKAGES:
                    assert alias.name in modules, f"{path}:{node.lineno}: no module {alias.name}"
                    found.add(alias.name)
    return found


def inversions(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Every import of a module from a higher layer than the importer's, less the listed exceptions."""
    return sorted((a, b) for a, imported in graph.items() for b in imported
                  if rank(b) > rank(a) and (a, b) not in EXCEPTIONS)


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


def _graph() -> dict[str, set[str]]:
    files = project_files()
    # A package's __init__ re-exporting its modules is not an import of a layer above: packages are left out.
    return {module: imports(path, set(files)) - {module} for module, path in files.items()}


def test_no_module_imports_itself_through_others():
    assert circles(_graph()) == []
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]  # the check can fail


def test_each_layer_imports_only_those_below_it():
    graph = _graph()
    assert {rank(m) for m in graph} == set(range(9))  # every layer has modules, and every module a layer
    assert inversions(graph) == []
    # The check can fail: the world reading the agent, and a run directory drawing a command.
    assert inversions({"imrl_jax.world.tasks": {"imrl_jax.agent.lifetime", "imrl_jax.config"},
                       "imrl_jax.runs.rundir": {"imrl_jax.commands.evolve"}}) == [
        ("imrl_jax.runs.rundir", "imrl_jax.commands.evolve"), ("imrl_jax.world.tasks", "imrl_jax.agent.lifetime")]


def test_a_command_by_its_short_name_is_no_import(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("def f():\n    from imrl_jax import evolve\n")
    assert imports(str(path), set(project_files())) == {"imrl_jax"}  # an attribute of the package, not a module
    path.write_text("import imrl_jax.evolve\n")
    try:
        imports(str(path), set(project_files()))
    except AssertionError as error:
        assert "no module imrl_jax.evolve" in str(error)
    else:
        raise AssertionError("imrl_jax.evolve was taken for a module")


def test_no_module_is_longer_than_one_concept():
    lengths = {module: sum(1 for _ in open(path)) for module, path in project_files().items()}
    assert {m: n for m, n in lengths.items() if n > MAX_LINES} == {}


def test_every_command_runs_by_its_short_name():
    """``python -m imrl_jax.NAME`` finds imrl_jax/commands/NAME.py and runs it (its --help, in one interpreter)."""
    folder = os.path.join(ROOT, "imrl_jax", "commands")
    commands = sorted(name[:-3] for name in os.listdir(folder) if name.endswith(".py")
                      and 'if __name__ == "__main__"' in open(os.path.join(folder, name)).read())
    code = ("import importlib.util, runpy, sys\n"
            f"for name in {commands!r}:\n"
            "    print(name, importlib.util.find_spec('imrl_jax.' + name).origin)\n"
            "    sys.argv = [name, '--help']\n"
            "    try:\n"
            "        runpy.run_module('imrl_jax.' + name, run_name='__main__', alter_sys=True)\n"
            "    except SystemExit as done:\n"
            "        assert done.code in (0, None), (name, done.code)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    found = [line.split() for line in out.stdout.splitlines() if line.split()[:1] and line.split()[0] in commands]
    assert found == [[c, os.path.join(folder, f"{c}.py")] for c in commands]
    assert commands == sorted(("baselines", "bench", "compare", "demo", "evolve", "gpu_check", "landscape_run",
                               "learning_test", "render", "runspec"))  # README's and COMMANDS.md's commands
