"""Runs named by what they compute (imrl_jax.runs.runspec): the key follows the model, committed runs keep theirs."""

import json
import os
import shutil

import pytest
from helpers import RESULTS, stop_after_first

from imrl_jax import conditions
from imrl_jax.runs import runspec
from imrl_jax.commands import runspec as runspec_command
from imrl_jax.config import PRESETS, make_config
from imrl_jax.runs.runspec import DuplicateRunError, RunSpec


def test_every_committed_run_keeps_its_recorded_key_and_no_two_share_one():
    """Each recorded evolution keeps its key (run_keys.json), and every run under the results, recorded or newer,
    maps to one key: index() refuses two directories of one run."""
    with open(os.path.join(RESULTS, "run_keys.json")) as f:
        recorded = json.load(f)
    found = {folder: key for key, folder in runspec.index(RESULTS).items()}
    assert {folder: found.get(folder) for folder in recorded} == recorded
    assert len(found) == len(runspec.run_dirs(RESULTS)) >= len(recorded) >= 49
    assert all(len(key) == runspec.KEY_LENGTH for key in recorded.values())


def test_two_configs_share_a_key_exactly_when_they_are_the_same_model():
    """Over every condition under every preset: same key <=> Config.model_differences finds nothing."""
    configs = [make_config(preset, condition=name) for name in conditions.NAMES for preset in PRESETS]
    pairs = same = 0
    for a in configs:
        for b in configs:
            if a.condition == b.condition:
                pairs += 1
                share = RunSpec.make(a, [0]).key() == RunSpec.make(b, [0]).key()
                assert share == (not a.model_differences(b)), (a.condition, a.model_differences(b))
                same += share
    assert pairs == len(conditions.NAMES) * len(PRESETS) ** 2 and len(configs) < same < pairs


def test_minus_zero_is_zero_in_a_key():
    """``--set gamma=-0`` is the run of ``gamma=0`` (a study asking for 0 finds it); -0.0 == 0.0 in the model too."""
    config = make_config("small", condition="LE-LS")
    zero, minus = config.replace(gamma=0.0), config.replace(gamma=-0.0)
    assert not zero.model_differences(minus)
    assert RunSpec.make(minus, [0]).key() == RunSpec.make(zero, [0]).key() != RunSpec.make(config, [0]).key()


def test_what_is_and_is_not_part_of_a_run():
    config = make_config("paper", condition="EE-LS")
    key = RunSpec.make(config, [0, 1]).key()
    # How it is computed, and how far it has come, are not.
    assert RunSpec.make(config.replace(step_kernel="pallas", kernel_retina="points", scan_unroll=2, num_generations=7),
                        [0, 1]).key() == key
    assert RunSpec.make(config.replace(childhood_steps=10), [0, 1]).key() == key  # EE-LS has no childhood
    assert RunSpec.make(config, [0, 1], {"strategy": "ga", "settings": {}}).key() == key  # the GA, recorded
    # The model, the seeds and the search are.
    assert RunSpec.make(config.replace(target_radius=12.0), [0, 1]).key() != key
    assert RunSpec.make(config, [0, 2]).key() != key
    assert RunSpec.make(config.replace(target_radius=12), [0, 1]).key() == RunSpec.make(
        config.replace(target_radius=12.0), [0, 1]).key()  # one value, whether written 12 or 12.0
    snes = RunSpec.make(config, [0, 1], {"strategy": "snes", "settings": {}})
    assert snes.key() != key
    assert RunSpec.make(config, [0, 1], {"strategy": "snes", "settings": {"sigma_init": 0.3}}).key() != snes.key()
    assert snes.identity()["search"] == {"strategy": "snes", "settings": {}}


def _copy_run(source: str, dest) -> None:
    os.makedirs(dest)
    shutil.copy(os.path.join(RESULTS, source, "config.json"), os.path.join(dest, "config.json"))


def test_locate_finds_a_run_wherever_it_lies_and_places_a_new_one_by_its_key(tmp_path):
    folder = sorted(json.load(open(os.path.join(RESULTS, "run_keys.json"))))[0]
    _copy_run(folder, tmp_path / "some" / "study" / "run")
    spec = RunSpec.from_run_dir(str(tmp_path / "some" / "study" / "run"))
    assert runspec.locate(str(tmp_path), spec) == (str(tmp_path / "some" / "study" / "run"), True)
    other = RunSpec.make(spec.config, [*spec.seeds, 99], spec.identity()["search"])
    assert runspec.locate(str(tmp_path), other) == (str(tmp_path / "runs" / other.key() / "evolve"), False)


def test_two_directories_of_one_run_are_refused_naming_both(tmp_path, capsys):
    folder = sorted(json.load(open(os.path.join(RESULTS, "run_keys.json"))))[0]
    _copy_run(folder, tmp_path / "a")
    _copy_run(folder, tmp_path / "b")
    with pytest.raises(DuplicateRunError, match=f"{tmp_path / 'b'} and {tmp_path / 'a'} hold the same run"):
        runspec.index(str(tmp_path))
    assert runspec_command.main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "hold the same run" in err
    assert runspec_command.main([str(tmp_path / "missing")]) == 2
    assert capsys.readouterr().err == f"error: root: {str(tmp_path / 'missing')!r} is not a folder\n"


def test_tests_from_scratch_are_indexed_by_what_they_compute(tmp_path):
    """Each committed SLE or EXT-LS test has a key of its own; a copy elsewhere is the same test, refused as a run
    is; a test of evolved genomes is not indexed (its run is)."""
    known = runspec.test_index(RESULTS)
    assert os.path.join("claims", "skills-bias0", "test", "SLE") in known.values()
    assert len(set(known.values())) == len(known) >= 18
    assert not any("goals" in folder for folder in known.values())  # EE-LS-T's tests are of evolved genomes
    for name in ("a", "b"):
        shutil.copytree(os.path.join(RESULTS, "claims", "skills-bias0", "test", "SLE"), tmp_path / name,
                        ignore=shutil.ignore_patterns("*.npz", "*.png"))
    with pytest.raises(runspec.DuplicateRunError, match="same learning test"):
        runspec.test_index(str(tmp_path))


def test_an_unreadable_test_or_two_folders_of_one_run_are_one_line_and_exit_2(tmp_path, capsys):
    """A steady.json of a test from scratch that is not JSON, or whose config names no field of ours, is a
    RunDirError naming the file; the command reports two folders of one run in one line, exit 2."""
    from imrl_jax.runs.rundir import RunDirError

    folder = tmp_path / "t"
    folder.mkdir()
    (folder / "steady.json").write_text("{not json")
    with pytest.raises(RunDirError, match="steady.json"):
        runspec.test_index(str(tmp_path))
    steady = json.loads(open(os.path.join(RESULTS, "claims", "skills-bias0", "test", "SLE", "steady.json")).read())
    (folder / "steady.json").write_text(json.dumps(dict(steady, config=dict(steady["config"], bogus_field=1))))
    with pytest.raises(RunDirError, match="steady.json is unreadable"):
        runspec.test_index(str(tmp_path))
    for copy in ("a", "b"):
        shutil.copytree(os.path.join(RESULTS, "goals", "EE-LS-T", "evolve"), tmp_path / "runs" / copy,
                        ignore=shutil.ignore_patterns("checkpoints", "resume_checkpoint", "*.npz", "*.png"))
    assert runspec_command.main([str(tmp_path / "runs")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "hold the same run" in err and err.count("\n") == 1
    assert runspec_command.main([str(tmp_path / "none")]) == 2 and "not a folder" in capsys.readouterr().err


def test_a_test_from_scratch_is_found_by_its_key_while_it_runs(tmp_path, monkeypatch):
    """Interrupted after its first run, an SLE test is indexed (its partial/spec.json) under the key its finished
    steady.json gives, so a second study asking for it goes on with it; a second begun copy is refused."""
    from imrl_jax.commands import learning_test

    argv = ["--cond", "SLE", "--runs", "2", "--best", "1", "--tests", "1", "--task-steps", "200", "--bins", "2",
            "--steady-steps", "100", "--chunks", "1", "--quiet", "--out", str(tmp_path / "results" / "sle")]
    real, calls = stop_after_first(monkeypatch, learning_test, "run_tests")
    with pytest.raises(KeyboardInterrupt):
        learning_test.main(argv)
    begun = runspec.test_index(str(tmp_path / "results"))
    assert list(begun.values()) == ["sle"]
    shutil.copytree(tmp_path / "results" / "sle", tmp_path / "results" / "copy")
    with pytest.raises(runspec.DuplicateRunError, match="same learning test"):
        runspec.test_index(str(tmp_path / "results"))
    shutil.rmtree(tmp_path / "results" / "copy")
    monkeypatch.setattr(learning_test, "run_tests", real)
    assert learning_test.main(argv) == 0
    assert runspec.test_index(str(tmp_path / "results")) == begun  # the finished test: the same key and folder
