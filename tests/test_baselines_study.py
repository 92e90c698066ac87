"""The committed baselines study (experiments/baselines.py): its stages and its figure, which need no brax."""

import json
import os

from helpers import ROOT

from imrl_jax.commands import baselines


def test_the_study_finds_every_committed_baseline_and_its_commands_made_them():
    """python -m experiments list baselines: 0 stages left, each the committed folder; each stage's command, parsed,
    asks for the settings its summary.json recorded."""
    from experiments.baselines import TABLE
    from experiments.harness.reproduce import stage_done

    stages, scale = TABLE.all_stages()
    assert [s.out_dir for s in stages] == [os.path.join("experiments", "results", "baselines", name)
                                           for name in ("ppo_1M", "es_1M", "ppo_5M", "es_5M")]
    assert all(s.kind == "baseline" and stage_done(s, scale) for s in stages)
    for stage in stages:
        command = TABLE.stage_command(stage)[0]
        assert command[1:3] == ["-m", "imrl_jax.baselines"]
        args = baselines.parser().parse_args(command[3:])
        with open(os.path.join(ROOT, stage.out_dir, "summary.json")) as f:
            settings = json.load(f)["settings"]
        assert (args.out, args.agent, args.steps, args.seeds, args.evals) == (
            stage.out_dir, settings["agent"], settings["steps"], settings["seeds"], settings["num_evals"]), stage.name


def test_the_study_draws_the_baselines_beside_the_paper_scale_where_it_has_tests(tmp_path, capsys):
    """The report: nothing to draw before a baseline has finished; comparison.png of what has; the learning tests
    of the paper scale once it has any, else the cpu scale's."""
    import dataclasses
    import shutil

    from experiments.baselines import TABLE

    table = dataclasses.replace(TABLE, results=str(tmp_path / "results"), out=str(tmp_path / "baselines"))
    assert table.report() == 0 and "nothing to draw" in capsys.readouterr().out
    assert table.tests_dir() == str(tmp_path / "results" / "cpu")
    steady = tmp_path / "results" / "paper" / "skills" / "test" / "LE-LS" / "steady.json"
    steady.parent.mkdir(parents=True)
    steady.write_text("{}")
    assert table.tests_dir() == str(tmp_path / "results" / "paper")
    committed = os.path.join(ROOT, "experiments", "results", "baselines", "es_5M")
    shutil.copytree(committed, tmp_path / "baselines" / "es_5M")
    assert table.report() == 0
    assert os.path.getsize(tmp_path / "baselines" / "comparison.png") > 10_000
