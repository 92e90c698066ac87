"""``python -m experiments``: every study found by itself, listed, run and reported in order."""

import sys

import pytest

from experiments import __main__ as cli
from experiments import study as S

ORDER = ["selector-sweep", "timescale", "novel-tasks", "claims-screen", "reproduction", "claims-experts", "search",
         "future-work", "reproduction-cpu", "goals", "childhood", "baselines"]


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
    from experiments import executor

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
        "from experiments.study import Study\n"
        "STUDIES = (Study('mine', 'my_study', 'docs/MINE.md', 0.5),)\n"
        "def all_stages():\n    return [], {}\n")
    monkeypatch.setattr(experiments, "__path__", [*experiments.__path__, str(tmp_path)])
    monkeypatch.syspath_prepend(str(tmp_path))
    assert list(S.studies()) == ["mine", *ORDER]
    (tmp_path / "my_copy.py").write_text("from my_study import STUDIES\n")
    with pytest.raises(ValueError, match="two studies are named 'mine'"):
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
                   "experiments.baselines --report"]


def test_ctrl_c_waits_for_the_study_to_stop_and_stops_with_one_line(monkeypatch, capsys):
    """The study got the same Ctrl-C: it is waited for (it keeps what its stages finished), not killed."""
    ran, processes = [], []
    monkeypatch.setattr(cli.subprocess, "Popen", _fake_run(ran, interrupt=True, processes=processes))
    assert cli.main(["run"]) == 130
    assert ran == ["experiments.selector_sweep"] and processes[0].waits == 2 and not processes[0].killed
    assert capsys.readouterr().err.strip() == ("interrupted in study selector-sweep: run the same command again to "
                                               "go on")


def test_bad_fan_out_options_exit_2(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["run", "search", "--jobs", "0"])
    assert stop.value.code == 2 and "--jobs: must be a whole number of at least 1, got '0'" in capsys.readouterr().err


def test_an_unknown_study_is_one_line_and_exit_2(capsys):
    assert cli.main(["run", "serch"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: study: unknown study 'serch' (choose from all, selector-sweep, timescale,") and err.count("\n") == 1
