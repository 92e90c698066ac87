"""``python -m experiments``: every study found by itself, listed, run and reported in order."""

import json
import os
import sys

import pytest
from attack import HOSTILE_INTS, HOSTILE_TEXTS, assert_contract, assert_refused, attack, damage
from helpers import write_lock

from experiments import __main__ as cli
from experiments.harness import runner
from experiments.harness import study as S
from imrl_jax.runs.cli import UsageError

ORDER = ["selector-sweep", "timescale", "novel-tasks", "claims-screen", "reproduction", "claims-experts", "search",
         "future-work", "reproduction-cpu", "goals", "childhood", "baselines", "worlds"]


def test_every_study_is_found_in_order():
    found = S.studies()
    assert list(found) == ORDER
    assert found["claims-experts"].command() == [sys.executable, "-m", "experiments.claims_study", "experts"]
    assert found["reproduction"].command(report=True) == [sys.executable, "-m", "experiments.reproduction", "paper",
                                                           "--report"]


@pytest.mark.parametrize("name", ORDER)
def test_each_study_plans_and_lists_its_stages(name, capsys):
    """Its stages as its run plans them; ``list NAME`` shows each one, done or to run, where it writes."""
    stages, scale = S.studies()[name].stages()
    assert stages and scale and len({s.name for s in stages}) == len(stages)
    assert cli.main(["list", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"{name} (docs/") and len(lines) == 1 + len(stages)
    assert [line.strip().rsplit(": ", 1)[0] for line in lines[1:]] == [s.name for s in stages]


def test_the_goals_tests_wait_for_their_own_evolution():
    from experiments.harness import executor

    stages, _ = S.studies()["goals"].stages()
    waits = executor.needs(stages)
    assert waits["learning test EE-LS-T-faithful"] == ("evolve EE-LS-T-faithful",)
    assert waits["evolve LE-LS-2R"] == ()


def test_list_all_counts_what_is_left(capsys):
    assert cli.main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0].strip() for line in lines] == [*ORDER, "in all"]
    study = S.studies()["search"]
    left, count, hours = cli.remaining(study, rate=1.0)
    stages, scale = study.stages()
    assert count == len(stages) and left == sum(not cli.stage_done(s, scale) for s in stages)
    assert hours * 3600 == pytest.approx(sum(cli.cost_left(s, scale) for s in stages))


def test_a_new_study_is_its_module_alone(tmp_path, monkeypatch):
    """A module that declares STUDIES is found with nothing else to register; two of one name are refused."""
    import experiments

    (tmp_path / "my_study.py").write_text(
        "from experiments.harness.study import Study\n"
        "STUDIES = (Study('mine', 'my_study', 'docs/MINE.md', 0.5),)\n"
        "def all_stages():\n    return [], {}\n")
    monkeypatch.setattr(experiments, "__path__", [*experiments.__path__, str(tmp_path)])
    monkeypatch.syspath_prepend(str(tmp_path))
    assert list(S.studies()) == ["mine", *ORDER]
    (tmp_path / "my_copy.py").write_text("from my_study import STUDIES\n")
    with pytest.raises(UsageError, match="experiments.my_study: declares the study .mine., which experiments.my_copy"):
        S.studies()


class _Process:
    """A stand-in for a study's process: its exit code, or a Ctrl-C while it is waited for (the first wait)."""

    def __init__(self, code: int, interrupt: bool = False):
        self.code, self.interrupt, self.waits, self.killed = code, interrupt, 0, False

    def wait(self):
        self.waits += 1
        if self.interrupt and self.waits == 1:
            raise KeyboardInterrupt
        return self.code

    def kill(self):
        self.killed = True


def _fake_run(ran, fail=None, interrupt=False, processes=None):
    def popen(command, env):
        command = command[4:] if command[1:2] == ["-c"] else command  # the launcher that ties it to its runner
        ran.append(" ".join(command[2:]))
        assert env["PYTHONPATH"].split(":")[0] == cli.environment()["PYTHONPATH"].split(":")[0]
        process = _Process(3 if command[2] == fail else 0, interrupt)
        (processes if processes is not None else []).append(process)
        return process

    return popen


def test_studies_run_in_order_and_a_failure_stops_the_rest(monkeypatch, capsys):
    ran = []
    monkeypatch.setattr(cli.subprocess, "Popen", _fake_run(ran, fail="experiments.reproduction"))
    assert cli.main(["run", "all"]) == 3
    assert ran == ["experiments.selector_sweep", "experiments.timescale", "experiments.novel_tasks",
                   "experiments.claims_study screen", "experiments.reproduction paper"]
    assert "study reproduction stopped with exit code 3" in capsys.readouterr().err
    ran.clear()
    assert cli.main(["run", "search"]) == 0 and ran == ["experiments.search"]
    ran.clear()
    assert cli.main(["run", "search", "--jobs", "3"]) == 0 and ran == ["experiments.search --jobs 3"]


def test_report_writes_each_studys_tables(monkeypatch):
    ran = []
    monkeypatch.setattr(cli.subprocess, "Popen", _fake_run(ran))
    assert cli.main(["report"]) == 0
    assert ran == ["experiments.timescale --report", "experiments.novel_tasks --report",
                   "experiments.claims_study screen --report", "experiments.reproduction paper --report",
                   "experiments.claims_study experts --report", "experiments.search --report",
                   "experiments.future_work --report", "experiments.reproduction cpu --report",
                   "experiments.goals --report", "experiments.childhood_study --report",
                   "experiments.baselines --report", "experiments.worlds --report"]


def test_ctrl_c_waits_for_the_study_to_stop_and_stops_with_one_line(monkeypatch, capsys):
    """The study got the same Ctrl-C: it is waited for (it keeps what its stages finished), not killed."""
    ran, processes = [], []
    monkeypatch.setattr(cli.subprocess, "Popen", _fake_run(ran, interrupt=True, processes=processes))
    assert cli.main(["run"]) == 130
    assert ran == ["experiments.selector_sweep"] and processes[0].waits == 2 and not processes[0].killed
    assert capsys.readouterr().err.strip() == ("interrupted in study selector-sweep: run the same command again to "
                                               "go on")


def test_bad_fan_out_options_exit_2(capsys):
    assert cli.main(["run", "search", "--jobs", "0"]) == 2
    err = capsys.readouterr().err
    assert err == "error: argument --jobs: must be a whole number of stages at once from 1 to 1,000, got '0'\n"


def test_an_unknown_study_is_one_line_and_exit_2(capsys):
    assert cli.main(["run", "serch"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: study: unknown study 'serch' (choose from all, selector-sweep, timescale,") and err.count("\n") == 1


def _attack(argv, root):
    return attack(cli.main, argv, str(root))


def test_every_option_takes_hostile_values_in_one_line_or_plans(tmp_path):
    """Every option of the parser (and the two positionals) given each hostile value: refused in one line naming it,
    exit 2, or planned; nothing written either way."""
    found = S.studies()
    planned, refused = [], 0
    for action in cli.parser(found)._actions:
        if not action.option_strings or action.nargs == 0:  # the positionals (below), --help
            continue
        flag = action.option_strings[-1]
        for value in HOSTILE_INTS if isinstance(action.default, int) else HOSTILE_TEXTS:
            argv = ["run", "selector-sweep", flag, value]
            if assert_contract(_attack(argv, tmp_path), flag, argv=argv) == "planned":
                planned.append(argv[2:])
            else:
                refused += 1
    for value in (*HOSTILE_TEXTS, "../x", "serch", "all/", "ALL"):
        # a value argparse takes for an option (-0,0) is named as an unrecognized argument
        also = (value,) if value.startswith("-") else ()
        for argv, name in ((["run", value], "study"), (["list", value], "study"), ([value], "action")):
            assert assert_contract(_attack(argv, tmp_path), name, *also, argv=argv) == "refused"
            refused += 1
    # every value out of bounds refused; what plans is a value in bounds (nothing ran, nothing was written)
    assert planned == [["--slurm-partition", "nan"], ["--slurm-partition", "1e8"], ["--slurm-partition", "0,0"],
                       ["--gpus-per-job", "0"], ["--gpus-per-job", "-0"]]
    assert refused == 137


@pytest.mark.parametrize("flag,value", [("--jobs", "0"), ("--jobs", "1001"), ("--gpus-per-job", "-1"),
                                        ("--gpus-per-job", "65"), ("--timeout-min", "0"), ("--timeout-min", "-5"),
                                        ("--timeout-min", "43201"), ("--slurm-partition", ""),
                                        ("--slurm-partition", "a b"), ("--executor", "k8s")])
def test_an_executor_option_out_of_bounds_is_one_line_naming_it(tmp_path, flag, value):
    assert_refused(_attack(["run", "search", flag, value], tmp_path), flag)


def _made_up_study(folder, monkeypatch, name="my_study", body=None):
    """A study module of its own in ``folder`` (found through the package's path), its results in ``folder/mine``."""
    import experiments

    for module in (name, f"experiments.{name}"):  # one made by an earlier test of its name
        monkeypatch.delitem(sys.modules, module, raising=False)
    (folder / f"{name}.py").write_text(body if body is not None else (
        "from experiments.harness.study import Study\n"
        f"STUDIES = (Study('mine', {name!r}, 'docs/MINE.md', 0.5, out='mine'),)\n"
        "def all_stages():\n    return [], {}\n"))
    monkeypatch.setattr(experiments, "__path__", [*experiments.__path__, str(folder)])
    monkeypatch.syspath_prepend(str(folder))


@pytest.mark.parametrize("how", ["empty", "truncated", "not json", "null", "a list", "NaN", "binary", "a folder",
                                 "no stages", "a stage of no object", "a cost of text", "an infinite time"])
def test_a_damaged_manifest_is_one_line_naming_it_and_its_repair(tmp_path, monkeypatch, how):
    """list, run, report and the study's own command refuse a damaged manifest.json in one line that names it and
    says how to repair it, exit 2, nothing written."""
    root = tmp_path / "root"
    (root / "mine").mkdir(parents=True)
    _made_up_study(tmp_path, monkeypatch)
    path = root / "mine" / "manifest.json"
    good = dict(study="mine", sizes={}, stages={"measure a": dict(command="python -m a", seconds=1.0, cost=5)})
    path.write_text(json.dumps(good))
    edits = {"no stages": {"study": "mine"}, "a stage of no object": dict(good, stages={"a": 3}),
             "a cost of text": dict(good, stages={"a": dict(command="x", cost="5")}),
             "an infinite time": dict(good, stages={"a": dict(command="x", seconds=float("inf"))})}
    if how == "a folder":
        path.unlink()
        path.mkdir()
    elif how in edits:
        path.write_text(json.dumps(edits[how]))
    else:
        damage(str(path), how)
    for argv in (["list", "mine"], ["run", "mine"], ["report", "mine"]):
        outcome = _attack(argv, root)
        assert_refused(outcome, "manifest.json", argv=argv)
        assert "remove " in outcome.stderr and "to start a new one" in outcome.stderr
    for argv in ([], ["--report"], ["--jobs", "2"]):
        own = attack(lambda a: runner.study_main(a, "mine", "mine", lambda: ([], {}), None, lambda: 0), argv, str(root))
        assert_refused(own, "manifest.json", argv=argv)


@pytest.mark.parametrize("body,named", [
    ("raise RuntimeError('boom')\n", "experiments.broken_study"),
    ("def f(:\n", "experiments.broken_study"),
    ("import sys\nsys.exit(3)\n", "experiments.broken_study"),
    ("STUDIES = ('not a study',)\n", "experiments.broken_study"),
    ("from my_study import STUDIES\n", "experiments.my_study")])
def test_a_broken_study_module_or_two_studies_of_one_name_is_one_line(tmp_path, monkeypatch, body, named):
    """A study module that raises on import, has a syntax error, exits, declares no Study, or two studies of one name:
    one line naming the module, exit 2, for list, run and report."""
    _made_up_study(tmp_path, monkeypatch)
    _made_up_study(tmp_path, monkeypatch, "broken_study", body)
    root = tmp_path / "root"
    root.mkdir()
    for argv in (["list"], ["run", "search"], ["report", "mine"]):
        assert_refused(_attack(argv, root), named, argv=argv)


def test_run_plans_every_study_it_will_run_and_refuses_one_another_runner_holds(tmp_path, monkeypatch):
    """The plan of ``run`` holds the studies chosen and the runner's options, checked; a study whose runner is alive
    (its lock) is refused in one line before anything runs."""
    root = tmp_path / "root"
    root.mkdir()
    _made_up_study(tmp_path, monkeypatch)
    outcome = _attack(["run", "mine", "--jobs", "2"], root)
    assert outcome.planned and outcome.plan.options == ("--jobs", "2") and [s.name for s in outcome.plan.studies] == [
        "mine"]
    write_lock(str(root / "mine" / "logs"), os.getppid())  # a live process: as another runner would
    assert_refused(_attack(["run", "mine"], root), "is being run by", argv=["run", "mine"])
    assert _attack(["list", "mine"], root).planned  # list is no runner: it reads alone


def test_a_studys_own_command_takes_hostile_values_in_one_line_or_plans(tmp_path):
    """``python -m experiments.MODULE``'s options (experiments.harness.runner) given each hostile value: refused in one line
    naming the option, or planned; nothing written (its folder, lock and manifest included)."""
    def own(argv):
        return runner.study_main(argv, "mine", "mine", lambda: ([], {}), None, lambda: 0)

    planned = []
    for action in runner.parser("mine")._actions:
        if not action.option_strings or action.nargs == 0:  # --help, --report
            continue
        flag = action.option_strings[-1]
        for value in HOSTILE_INTS if isinstance(action.default, int) else HOSTILE_TEXTS:
            if assert_contract(attack(own, [flag, value], str(tmp_path)), flag, argv=[flag, value]) == "planned":
                planned.append([flag, value])
    assert planned == [["--slurm-partition", "nan"], ["--slurm-partition", "1e8"], ["--slurm-partition", "0,0"],
                       ["--gpus-per-job", "0"], ["--gpus-per-job", "-0"]]
    assert_contract(attack(own, ["--report", "--jobs", "2"], str(tmp_path)))
    assert not os.listdir(tmp_path)
