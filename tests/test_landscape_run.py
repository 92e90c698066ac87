"""``python -m imrl_jax.landscape_run``: a run's generations measured, their parents taken from the run itself."""

import json
import os
import shutil
import socket
import sys

import numpy as np
import pytest
from attack import HOSTILE_FILE_BYTES, HOSTILE_INTS, HOSTILE_TEXTS, assert_contract, assert_refused, attack, damage, \
    edit_json
from helpers import evolve_args

from imrl_jax.runs import cli
from imrl_jax import conditions
from imrl_jax.commands import evolve, landscape_run
from imrl_jax.runs.rundir import best_genomes, load_run

SIZES = dict(seeds=2, population=6, parents=2, task_steps=1000, bins=2)
RUN = evolve_args(**SIZES, generations=3) + ["--set", "target_radius=40"]
SMALL = dict(lives=2, num_parents=4, num_mutants=3, num_walks=2, walk_length=3, num_random=6, chunk=8)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("landscape") / "run")
    assert evolve.main([*RUN, "--out", out]) == 0
    return out


def test_parents_are_the_runs_own_generations(run_dir, tmp_path):
    """Generation 0 is the seed's draw (the one-generation run's evaluated population), the last the final
    population's best, and a generation between is replayed bitwise (its best fitness is the run's)."""
    config, seeds = evolve.read_config(run_dir)
    first = str(tmp_path / "first")
    assert evolve.main([*evolve_args(**SIZES, generations=1), "--set", "target_radius=40", "--out", first]) == 0
    parents, _ = landscape_run.parents_at(run_dir, config, seeds, 1, 0, 4, str(tmp_path), None)
    np.testing.assert_array_equal(parents, load_run(first).evaluated[1, :4])
    parents, source = landscape_run.parents_at(run_dir, config, seeds, 1, 2, 4, str(tmp_path), None)
    np.testing.assert_array_equal(parents, best_genomes(load_run(run_dir), 4)[1])
    assert source == {"source": "final_population.npz"}
    parents, source = landscape_run.parents_at(run_dir, config, seeds, 1, 1, 4, str(tmp_path), None)
    assert source["replay_matches_run"] is True and parents.shape == (4, config.num_genes)
    history = os.path.join(run_dir, "history.csv")
    with open(history) as f:
        text = f.read()
    lines = text.splitlines()
    row = next(i for i, line in enumerate(lines) if line.startswith("1,1,"))
    fields = lines[row].split(",")
    fields[2] = f"{float(fields[2]) + 0.01:.6f}"  # a run whose history says otherwise is caught
    try:
        with open(history, "w") as f:
            f.write("\n".join(lines[:row] + [",".join(fields)] + lines[row + 1:]) + "\n")
        _, source = landscape_run.parents_at(run_dir, config, seeds, 1, 1, 4, str(tmp_path), None)
        assert source["replay_matches_run"] is False
    finally:
        with open(history, "w") as f:
            f.write(text)


def test_every_piece_is_measured_once_and_a_second_call_goes_on_from_them(run_dir, tmp_path, monkeypatch):
    out = str(tmp_path / "m")
    said, written = [], []
    atomic = landscape_run.write_atomic
    monkeypatch.setattr(landscape_run, "write_atomic", lambda path, data: (written.append(path), atomic(path, data)))
    result = landscape_run.run(run_dir, out, generations="0,last", cuts=(0.0,), log=said.append, **SMALL)
    # landscape.json after each of the 6 pieces and once more, then result.json, each atomically: a kill leaves
    # a whole record
    assert [os.path.basename(p) for p in written] == ["landscape.json"] * 7 + ["result.json"]
    assert sorted(result["pieces"]) == sorted(f"{what}, {learning}" for what in ("random genomes", "generation 0",
                                                                                   "generation 2")
                                              for learning in ("learning", "cut 0"))
    assert len(said) == 1 + 6 and said[0].startswith("measuring generation(s) 0, 2 of seed 0: ")  # its cost first
    for name, piece in result["pieces"].items():
        if name.startswith("generation"):
            shares = piece["share_neutral"] + piece["share_deleterious"] + piece["share_beneficial"]
            assert shares == pytest.approx(1.0) and len(piece["rho"]) == 3
        else:
            assert len(piece["fitness"]) == 6 and piece["mean"] == pytest.approx(np.mean(piece["fitness"]), abs=1e-5)
    # EE-LS with its selector's learning cut to nothing: the same genomes, another landscape.
    assert result["pieces"]["generation 2, learning"] != result["pieces"]["generation 2, cut 0"]
    said.clear()
    again = landscape_run.run(run_dir, out, generations="0,last", cuts=(0.0,), log=said.append, **SMALL)
    assert len(said) == 1 and said[0].endswith("; the pieces measured before are not measured again")
    assert again == result
    with open(os.path.join(out, "result.json")) as f:
        assert json.load(f) == result


@pytest.mark.parametrize("args, message", [
    (["--generations", "0,7"], "--generations: 7 is not a generation of the run (0..2)"),
    (["--generations", "first"], "--generations: expected integers or 'last'"),
    (["--cut", "2"], "--cut: fraction: must be in [0, 1] (got 2.0)"),
    (["--cut", "x"], "--cut: expected fractions separated by commas"),
    (["--seed", "5"], "--seed: 5 is not a seed of"),
    (["--lives", "1"], "--lives: must be at least 2 (got 1)"),
    (["--parents", "7"], "--parents: at most the population size (6; got 7)"),
    (["--parents", "4", "--walks", "5"], "--walks: at most --parents (4; got 5)"),
])
def test_bad_input_exits_2_in_one_line_and_writes_nothing(run_dir, tmp_path, capsys, args, message):
    out = tmp_path / "m"
    assert landscape_run.main([run_dir, "--out", str(out), "--parents", "4", "--walks", "2", "--generations", "0,last",
                               *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {message}") and "\n" not in err, err
    assert not out.exists()


def test_measures_of_other_settings_are_not_mixed(run_dir, tmp_path, capsys):
    out = tmp_path / "m"
    out.mkdir()
    (out / "landscape.json").write_text(json.dumps({"identity": {"seed": 0}, "pieces": {}}))
    assert landscape_run.main([run_dir, "--out", str(out), "--parents", "4", "--walks", "2", "--generations", "0"]) == 2
    assert "holds measures of other settings" in capsys.readouterr().err
    assert sorted(os.listdir(out)) == ["landscape.json"]


# ------------------------------------------------------------------------ attacks: nothing compiled, nothing written

#: A module of one's own with a row of the condition table (as tests/test_conditions.py's).
ROWS_MODULE = """
import dataclasses

from imrl_jax import conditions

ROW = dataclasses.replace(conditions.get("EE-LS"), name="EE-LS-mine", description="EE-LS, registered from a module")
"""
#: Sizes the tiny run (2 seeds of 4, 1 generation) takes.
TINY = ["--parents", "2", "--walks", "1", "--generations", "0,last"]


@pytest.fixture
def copied(tiny_run, tmp_path):
    """A copy of the tiny finished run at ``tmp_path/v/evolve/EE-LS`` (variant ``v`` for --best-genomes), and
    an --out beside it."""
    run = str(tmp_path / "v" / "evolve" / "EE-LS")
    shutil.copytree(tiny_run, run)
    return run, str(tmp_path / "m")


def _planned(run, out, root, *args):
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY, *args], root)
    assert assert_contract(outcome) == "planned", outcome.stderr
    return outcome.plan


def _rewrite_population(run, change):
    path = os.path.join(run, "final_population.npz")
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files}
    change(arrays)
    np.savez(path, **arrays)


def _unfinished(run, generations=3):
    """The run as if killed after its first generation of ``generations`` (its config asks for more)."""
    edit_json(os.path.join(run, "config.json"), lambda info: info["config"].update(num_generations=generations))


def test_an_unfinished_run_is_refused_unless_allowed_and_a_generation_never_reached_always(copied, tmp_path):
    run, out = copied
    _unfinished(run)
    assert_refused(attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path)), "--allow-unfinished")
    for generations in ("1", "0,2", "2"):  # reached by the config, never by the run
        outcome = attack(landscape_run.main, [run, "--out", out, *TINY, "--allow-unfinished", "--generations",
                                              generations], str(tmp_path))
        assert_refused(outcome, "--generations")
        assert "past the 1 generation(s) the run has evaluated" in outcome.stderr
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY, "--allow-unfinished"], str(tmp_path))
    assert assert_contract(outcome) == "planned"
    assert "warning: " in outcome.stderr and "1 of its 3 generations" in outcome.stderr
    assert outcome.plan.generations == [0] and outcome.plan.done == 1  # last: the last the run evaluated


def test_a_run_still_being_written_is_unfinished(copied, tmp_path):
    run, out = copied
    with open(os.path.join(run, ".lock"), "w") as f:  # this process: alive
        json.dump({"pid": os.getpid(), "host": socket.gethostname(), "start": 0}, f)
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path))
    assert_refused(outcome, "--allow-unfinished")
    assert f"is being written by pid {os.getpid()}" in outcome.stderr


def test_the_records_state_the_generations_measured_and_the_runs_done(copied, tmp_path):
    """Every piece already measured: execute only writes the records (nothing compiled), which say what was."""
    run, out = copied
    _unfinished(run)
    plan = _planned(run, out, str(tmp_path), "--allow-unfinished")
    os.makedirs(out)
    pieces = {"random genomes, learning": {"mean": 0.0}, "generation 0, learning": {"generation": 0}}
    with open(os.path.join(out, "landscape.json"), "w") as f:
        json.dump({"identity": plan.identity, "pieces": pieces}, f)
    assert cli.execute(plan) == 0
    for name in ("landscape.json", "result.json"):
        with open(os.path.join(out, name)) as f:
            record = json.load(f)
        assert record["generations"] == [0] and record["generations_done"] == 1 and record["num_generations"] == 3
        assert "1 of its 3 generations" in record["unfinished"] and record["pieces"] == pieces
    assert sorted(os.listdir(out)) == ["landscape.json", "result.json"]  # the lock gone


@pytest.mark.parametrize("damage_it", ["NaN fitness", "inf genomes", "wrong width", "wrong population"])
def test_a_damaged_final_population_is_refused(copied, tmp_path, damage_it):
    run, out = copied

    def change(arrays):
        if damage_it == "NaN fitness":
            arrays["fitness"][0, 1] = np.nan
        elif damage_it == "inf genomes":
            arrays["evaluated"][1, 0, 3] = np.inf
        elif damage_it == "wrong width":
            arrays["evaluated"] = arrays["evaluated"][:, :, :-1]
        else:
            arrays["evaluated"], arrays["fitness"] = arrays["evaluated"][:, :3], arrays["fitness"][:, :3]

    _rewrite_population(run, change)
    assert_refused(attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path)), "final_population.npz")


@pytest.mark.parametrize("damage_it", [None, "NaN genomes", "inf fitness", "wrong width", "other seeds", "2 kept"])
def test_damaged_best_genomes_are_refused(copied, tmp_path, damage_it):
    run, out = copied
    kept = str(tmp_path / "best_genomes.npz")
    genomes = np.random.default_rng(0).uniform(-1, 1, (2, 3, 222)).astype(np.float32)
    seeds, fitness = np.array([0, 1]), np.zeros((2, 3), np.float32)
    if damage_it == "NaN genomes":
        genomes[0, 0, 0] = np.nan
    elif damage_it == "inf fitness":
        fitness[1, 2] = -np.inf
    elif damage_it == "wrong width":
        genomes = genomes[..., :111]
    elif damage_it == "other seeds":
        seeds = np.array([5, 6])
    elif damage_it == "2 kept":
        genomes, fitness = genomes[:, :2], fitness[:, :2]
    np.savez(kept, **{"v__EE-LS__genomes": genomes, "v__EE-LS__seeds": seeds, "v__EE-LS__fitness": fitness})
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY, "--parents", "3", "--best-genomes", kept],
                     str(tmp_path))
    if damage_it is None:
        assert assert_contract(outcome) == "planned"
    else:
        assert_refused(outcome, "--parents" if damage_it == "2 kept" else "--best-genomes")


@pytest.mark.parametrize("where, says", [
    ("the run", "is the run's own folder"), ("inside the run", "is inside the run"),
    ("around the run", "holds the run"), ("other files", "holds notes.txt"), ("a file", "is not a directory")])
def test_an_out_of_the_run_or_of_other_files_is_refused(copied, tmp_path, where, says):
    run, out = copied
    out = {"the run": run, "inside the run": os.path.join(run, "measures"), "around the run": str(tmp_path / "v"),
           "other files": out, "a file": out}[where]
    if where == "other files":
        os.makedirs(out)
        (tmp_path / "m" / "notes.txt").write_text("mine")
    elif where == "a file":
        (tmp_path / "m").write_text("mine")
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path))
    assert_refused(outcome, "--out")
    assert says in outcome.stderr


def test_an_out_of_this_commands_own_files_is_gone_on_from(copied, tmp_path):
    run, out = copied
    plan = _planned(run, out, str(tmp_path))
    os.makedirs(os.path.join(out, "landscape_replay-3"))
    with open(os.path.join(out, "landscape.json"), "w") as f:
        json.dump({"identity": plan.identity, "pieces": {}}, f)
    _planned(run, out, str(tmp_path))


def test_what_the_measures_cost_is_said_first(copied, tmp_path):
    """The plan says its lives (counted by hand: --random, then per generation the parents and their mutants, the
    walks and their steps, every genome --lives times), lane-steps, time and memory, before any piece."""
    run, out = copied
    plan = _planned(run, out, str(tmp_path), "--lives", "2", "--mutants", "3", "--walk-length", "4", "--random", "6")
    assert plan.generations == [0]  # 0 and last: the run's one generation
    lives = 2 * (6 + 1 * (2 * (1 + 3) + 1 * (1 + 4)))
    assert plan.cost.startswith(f"measuring generation(s) 0 of seed 0: {lives} lives a call, "
                                f"{lives * plan.config.lifetime_steps:,} lane-steps a call")
    assert plan.cost.endswith(" GiB of memory (an estimate)")


@pytest.mark.parametrize("options, differs", [
    (["--seed", "1"], "seed 0 there, 1 here"), (["--key", "7"], "key 0 there, 7 here"),
    (["--lives", "3"], "lives 4 there, 3 here"), (["--mutants", "5"], "mutants 9 there, 5 here"),
])
def test_measures_of_other_options_are_refused_naming_what_differs(copied, tmp_path, options, differs):
    run, out = copied
    plan = _planned(run, out, str(tmp_path))
    os.makedirs(out)
    with open(os.path.join(out, "landscape.json"), "w") as f:
        json.dump({"identity": plan.identity, "pieces": {}}, f)
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY, *options], str(tmp_path))
    assert_refused(outcome, "landscape.json")
    assert differs in outcome.stderr


def test_measures_of_another_run_are_refused(copied, tmp_path):
    run, out = copied
    plan = _planned(run, out, str(tmp_path))
    os.makedirs(out)
    with open(os.path.join(out, "landscape.json"), "w") as f:
        json.dump({"identity": {**plan.identity, "run_key": "0123456789abcdef"}, "pieces": {}}, f)
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path))
    assert_refused(outcome, "landscape.json")
    assert "run_key '0123456789abcdef' there" in outcome.stderr


@pytest.mark.parametrize("name", ["landscape.json", "result.json"])
@pytest.mark.parametrize("how", sorted(HOSTILE_FILE_BYTES))
def test_a_damaged_record_in_out_is_one_line_naming_it(copied, tmp_path, name, how):
    run, out = copied
    plan = _planned(run, out, str(tmp_path))
    os.makedirs(out)
    with open(os.path.join(out, name), "w") as f:
        json.dump({"identity": plan.identity, "pieces": {"random genomes, learning": {"mean": 0.5}}}, f)
    damage(os.path.join(out, name), how)
    assert_refused(attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path)), name)


def test_progress_is_written_atomically(copied, tmp_path, monkeypatch):
    """landscape.json and result.json go through rundir.write_atomic: a kill leaves the old or the new record."""
    run, out = copied
    plan = _planned(run, out, str(tmp_path))
    os.makedirs(out)
    with open(os.path.join(out, "landscape.json"), "w") as f:
        json.dump({"identity": plan.identity, "pieces": {"random genomes, learning": {}, "generation 0, learning": {}}},
                  f)
    written = []
    monkeypatch.setattr(landscape_run, "write_atomic", lambda path, data: written.append(os.path.basename(path)))
    assert plan.measure()["generations"] == [0]
    assert written == ["landscape.json", "result.json"]


LANES, TOTAL = "lives at once, above the limit", "lives in all, above the limit"


@pytest.mark.parametrize("argv, says", [
    (["--random", "1e8"], "argument --random: invalid int value"), (["--random", "100000000"], TOTAL),
    (["--chunk", "100000000"], LANES), (["--lives", "100000000"], LANES), (["--lives", "1"], "--lives: must be at"),
    (["--mutants", "100000000"], TOTAL), (["--walk-length", "100000000"], TOTAL),
    (["--walks", "100000000"], "--walks: at most --parents"), (["--parents", "100000000"], "--parents: at most"),
    (["--chunk", "200000"], "memory: the landscape measures needs"),  # 800,000 lives at once: lanes, not memory
    (["--key", "-1"], "--key: must be at least 0"), (["--key", "4294967296"], "--key: 4,294,967,296 is above"),
    (["--key", "18446744073709551616"], "--key"), (["--seed", "-1"], "--seed: -1 is not a seed"),
    (["--seed", "18446744073709551616"], "is not a seed"), (["--cut", "nan"], "--cut: fraction: must be in [0, 1]"),
    (["--cut", "1.5"], "--cut: fraction"), (["--cut", "0,,1"], "--cut: an empty item"),
    (["--cut", ","], "--cut: an empty item"), (["--cut=-0.5"], "--cut: fraction"),
    (["--cut", "inf"], "--cut: fraction"),
])
def test_every_size_and_value_is_bounded(copied, tmp_path, argv, says):
    run, out = copied
    outcome = attack(landscape_run.main, [run, "--out", out, *TINY, *argv], str(tmp_path))
    assert_refused(outcome, argv[0].split("=")[0], "memory")
    assert says in outcome.stderr


def test_a_registered_row_is_measured_with_register(copied, tmp_path, monkeypatch):
    run, out = copied
    (tmp_path / "my_rows.py").write_text(ROWS_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    edit_json(os.path.join(run, "config.json"), lambda info: info["config"].update(condition="EE-LS-mine"))
    try:
        outcome = attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path))
        assert_refused(outcome, "--register")
        outcome = attack(landscape_run.main, [run, "--out", out, *TINY, "--register", "my_rows:ROW"], str(tmp_path))
        assert assert_contract(outcome) == "planned" and outcome.plan.config.condition == "EE-LS-mine"
    finally:
        conditions.CONDITIONS.pop("EE-LS-mine", None)
        sys.modules.pop("my_rows", None)


def _hostile_cases():
    for action in landscape_run.parser()._actions:
        if action.nargs == 0:  # --help, --allow-unfinished: no value to attack
            continue
        flag = action.option_strings[0] if action.option_strings else None
        for value in HOSTILE_INTS if action.type is int else HOSTILE_TEXTS:
            yield pytest.param(flag, value, id=f"{flag or action.dest}={value[:12]!r}")


@pytest.mark.parametrize("flag, value", list(_hostile_cases()))
def test_hostile_values_of_every_option_keep_the_contract(copied, tmp_path, flag, value):
    run, out = copied
    try:
        if flag is None:  # the run itself
            argv, names = [value, "--out", out, *TINY], ("run", value) if value.strip() else ("run",)
        else:
            argv, names = [run, "--out", out, *TINY, flag, value], (flag,)
        assert_contract(attack(landscape_run.main, argv, str(tmp_path)), *names, argv=argv)
    finally:
        conditions.CONDITIONS.pop("EE-LS-mine", None)


@pytest.mark.parametrize("name", ["config.json", "history.csv", "final_population.npz"])
@pytest.mark.parametrize("how", sorted(HOSTILE_FILE_BYTES))
def test_a_damaged_file_of_the_run_is_one_line_naming_it(copied, tmp_path, name, how):
    """history.csv is read where the run kept no final population (its generations done) or a generation is
    replayed (its best checked): here the first."""
    run, out = copied
    if name == "history.csv":
        os.remove(os.path.join(run, "final_population.npz"))
    damage(os.path.join(run, name), how)
    assert_refused(attack(landscape_run.main, [run, "--out", out, *TINY], str(tmp_path)), name)
