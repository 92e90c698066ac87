"""A study as one entry the command line finds by itself: ``python -m experiments list|run|report NAME|all``.

A study module declares ``STUDIES``, a tuple of :class:`Study` (a module may hold several: the
claims map's screen and its claim 8 are two studies of one module). :func:`studies` imports every
module of the package and collects them, in the order their results are needed (``order``), so a
new study is its module and its document: nothing else registers it (docs/STUDIES.md).

It also holds what every study shares: where the results lie (``RESULTS``, the reproduction's
``REPRODUCTION``), the sizes of their runs (``SCALES``, ``SCREEN``), and the writers of a document's
table (:func:`write_table`, between its :func:`markers`) and of a measure's rows and result.json
(:func:`write_measure`, ``MEASURED``).
"""

from __future__ import annotations

import csv
import dataclasses
import importlib
import json
import os
import pkgutil
import sys

#: Where every study's results lie (relative to the repository's root, where the commands run).
RESULTS = os.path.join("experiments", "results")
#: The repository root: the folder above the experiments package.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
#: What a measure stage writes last, into its folder: its presence means the stage is done.
MEASURED = "result.json"
#: The paper's runs (the reproduction's), which other studies compare with and reuse.
REPRODUCTION = os.path.join(RESULTS, "paper")

#: The sizes of a study's runs: the paper's, one core's (a CPU reproduction) and a smoke test of the pipeline.
SCALES = {
    "paper": dict(seeds=10, generations=100, childhood_steps=150_000, task_steps=100_000, bins=100,
                  best=10, tests=10, test_steps=1_000_000, test_bins=100, steady_steps=100_000),
    "cpu": dict(seeds=5, generations=40, childhood_steps=30_000, task_steps=20_000, bins=20,
                best=10, tests=2, test_steps=200_000, test_bins=100, steady_steps=20_000),
    # A smoke test of the pipeline itself (seconds of compute; results mean nothing).
    "tiny": dict(seeds=2, generations=2, childhood_steps=400, task_steps=400, bins=2,
                 best=2, tests=1, test_steps=800, test_bins=4, steady_steps=200, population=6, parents=2),
}
#: A screen: the paper's lengths with 5 seeds, whose 5 best are learning-tested 4 times each.
SCREEN = dict(SCALES["paper"], seeds=5, best=5, tests=4)


def markers(what: str, study: str) -> tuple[str, str]:
    """The comments around a document's ``what`` that ``study``'s report writes: the first names its command."""
    return f"<!-- {what}: python -m experiments report {study} -->", f"<!-- end of {what} -->"


def write_table(path: str, text: str, start_marker: str, end_marker: str) -> None:
    """Put ``text`` between its markers in the document ``path`` (the rest of the document is kept)."""
    with open(path) as f:
        document = f.read()
    start, end = document.index(start_marker), document.index(end_marker)
    from imrl_jax.runs.rundir import write_atomic

    write_atomic(path, (document[:start + len(start_marker)] + "\n" + text + "\n" + document[end:]).encode())


@dataclasses.dataclass(frozen=True)
class Study:
    """A question asked of runs: its module's stages, its command to run them and the one to report."""

    name: str  # what the command line calls it
    module: str  # its module under experiments/
    document: str  # the document it writes into
    order: float  # its place in ``all`` (whole questions early)
    argv: tuple[str, ...] = ()  # its module's options for its stages ((): the module's default stages)
    report_argv: tuple[str, ...] | None = ("--report",)  # the options that write its report (None: a stage does)
    out: str | None = None  # its folder: manifest, logs (None: its module's OUT)

    def folder(self) -> str | None:
        """Where its manifest and its runner's lock lie: its ``out``, else its module's ``OUT`` (None: neither)."""
        if self.out is not None:
            return self.out
        return getattr(importlib.import_module(f"experiments.{self.module}"), "OUT", None)

    def stages(self):
        """Its stages (``reproduce.Stage``) and their scale, as its run would plan them now."""
        module = importlib.import_module(f"experiments.{self.module}")
        if self.argv and self.argv[0] in getattr(module, "TABLES", {}):  # a module of several tables
            return module.TABLES[self.argv[0]].all_stages()
        return module.all_stages()

    def command(self, report: bool = False, options: tuple[str, ...] = ()) -> list[str]:
        """The command line that runs (or goes on with) its stages with the runner's ``options`` (--jobs, --executor),
        or writes its report."""
        if report:
            return [sys.executable, "-m", f"experiments.{self.module}", *self.report_argv]
        return [sys.executable, "-m", f"experiments.{self.module}", *self.argv, *options]


def studies() -> dict[str, Study]:
    """Every study the package's modules declare, by name, in order; a module that cannot be imported, or two studies
    of one name, is a UsageError naming the module."""
    import experiments
    from imrl_jax.runs.cli import UsageError

    found: dict[str, Study] = {}
    declaring: dict[str, str] = {}  # each study's name -> the module that declares it
    for info in sorted(pkgutil.iter_modules(experiments.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        name = f"experiments.{info.name}"
        try:
            module = importlib.import_module(name)
        except (Exception, SystemExit) as error:  # noqa: BLE001 - whatever a study module does on import: one line
            text = str(error).splitlines()[0] if str(error) else ""
            raise UsageError(f"study module {name}: cannot be imported ({type(error).__name__}: {text[:200]}); "
                             f"fix or remove it") from None
        declared = getattr(module, "STUDIES", ())
        if not isinstance(declared, (tuple, list)) or not all(isinstance(s, Study) for s in declared):
            raise UsageError(f"study module {name}: STUDIES is not a tuple of experiments.harness.study.Study")
        for study in declared:
            if study.name in found:
                raise UsageError(f"study module {name}: declares the study {study.name!r}, which "
                                 f"{declaring[study.name]} declares too (two studies of one name)")
            found[study.name], declaring[study.name] = study, name
    return dict(sorted(found.items(), key=lambda item: item[1].order))


def environment() -> dict:
    """This environment with the repository root on the path (the studies are modules of the experiments package)."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (ROOT, os.environ.get("PYTHONPATH")) if p)}


def write_measure(out_dir: str, name: str, table: list[dict], command: str, digits: int | None = None,
                  **recorded) -> None:
    """A measure's rows (``table``) as ``out_dir/NAME.csv`` (floats to ``digits`` decimals, if given; a row may lack
    a column), then its result.json, which makes the measure done: its command, commit and ``recorded``; each
    written atomically (a kill leaves the measure not done, never a half file)."""
    import io

    from imrl_jax.runs.checkpoint import git_commit
    from imrl_jax.runs.rundir import make_dir, write_atomic

    make_dir(out_dir)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(dict.fromkeys(k for r in table for k in r)), restval="",
                            lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: f"{v:.{digits}f}" if digits is not None and isinstance(v, float) else v
                      for k, v in r.items()} for r in table)
    write_atomic(os.path.join(out_dir, f"{name}.csv"), text.getvalue().encode())
    write_atomic(os.path.join(out_dir, MEASURED),
                 json.dumps(dict(command=command, git_commit=git_commit(), **recorded), indent=2).encode())
