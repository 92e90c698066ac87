"""The notebooks run end to end at the tiny scale and are stored without outputs."""

import os
import sys

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("ipywidgets")

from jupyter_client.manager import KernelManager  # noqa: E402  (a dependency of nbclient)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NOTEBOOKS = os.path.join(ROOT, "notebooks")
NAMES = ["01_tour.ipynb", "02_sweeps.ipynb", "03_studies.ipynb", "04_world_of_ones_own.ipynb"]
#: Seconds a cell may take at the tiny scale before the test fails.
TIMEOUT = 120


class ThisPythonKernel(KernelManager):
    """The python3 kernel, run by the interpreter running the tests (the venv's), whatever is installed."""

    def format_kernel_cmd(self, extra_arguments=None):
        return [sys.executable, "-m", "ipykernel_launcher", "-f", self.connection_file]


def _read(name):
    return nbformat.read(os.path.join(NOTEBOOKS, name), as_version=4)


@pytest.mark.parametrize("name", NAMES)
def test_stored_without_outputs(name):
    for cell in _read(name).cells:
        if cell.cell_type == "code":
            assert cell.outputs == [], f"{name}: a code cell has stored outputs"
            assert cell.execution_count is None, f"{name}: a code cell has an execution count"


@pytest.mark.parametrize("name, task_set", [(NAMES[0], "paper"), pytest.param(NAMES[1], "novel",
                                                                               marks=pytest.mark.slow),
                                            (NAMES[2], "paper"), (NAMES[3], "paper")])
def test_runs_at_tiny_scale(name, task_set, monkeypatch):
    monkeypatch.setenv("IMRL_NOTEBOOK_SCALE", "tiny")
    monkeypatch.setenv("IMRL_TASK_SET", task_set)
    monkeypatch.setenv("JAX_PLATFORMS", "cpu")
    monkeypatch.delenv("IMRL_RUN_DIR", raising=False)
    # Less LLVM optimisation: the kernel compiles about twice as fast, and tiny runs are compile-bound.
    flags = os.environ.get("XLA_FLAGS", "")
    monkeypatch.setenv("XLA_FLAGS", f"{flags} --xla_backend_optimization_level=1".strip())
    notebook = _read(name)
    client = nbclient.NotebookClient(notebook, timeout=TIMEOUT, kernel_name="python3",
                                     kernel_manager_class=ThisPythonKernel,
                                     resources={"metadata": {"path": NOTEBOOKS}})
    client.execute()  # raises CellExecutionError, naming the cell, on any error
    errors = [out for cell in notebook.cells if cell.cell_type == "code"
              for out in cell.outputs if out.output_type == "error"]
    assert not errors
    assert any("image/png" in out.get("data", {}) for cell in notebook.cells if cell.cell_type == "code"
               for out in cell.outputs), "no figure was shown"
