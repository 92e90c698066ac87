"""``python -m imrl_jax.landscape_run``: a run's generations measured, their parents taken from the run itself."""

import json
import os

import numpy as np
import pytest
from helpers import evolve_args

from imrl_jax import evolve, landscape_run
from imrl_jax.rundir import best_genomes, load_run

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


def test_every_piece_is_measured_once_and_a_second_call_goes_on_from_them(run_dir, tmp_path):
    out = str(tmp_path / "m")
    said = []
    result = landscape_run.run(run_dir, out, generations="0,last", cuts=(0.0,), log=said.append, **SMALL)
    assert sorted(result["pieces"]) == sorted(f"{what}, {learning}" for what in ("random genomes", "generation 0",
                                                                                   "generation 2")
                                              for learning in ("learning", "cut 0"))
    assert len(said) == 6
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
    assert said == [] and again == result
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
    assert landscape_run.main([run_dir, "--out", str(out), "--parents", "4", "--walks", "2", "--generations", "0,last", *args]) == 2
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
