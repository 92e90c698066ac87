"""The future-work study's plan (each new row evolved or tested from scratch), and the evolved values evolve records."""

import os

import pytest

from experiments import future_work as study


def test_plan_evolves_the_evolved_rows_and_tests_the_others_from_scratch():
    stages = study.plan(["EV-LS", "EXT-LS-whole", "LE-LS-N6"])
    assert [s.name for s in stages] == ["evolve EV-LS", "learning test EV-LS", "learning test EXT-LS-whole",
                                        "evolve LE-LS-N6", "learning test LE-LS-N6"]
    evolve = study.stage_command(stages[3])[0]
    assert evolve[evolve.index("--cond") + 1] == "LE-LS-N" and "num_experts=6" in evolve
    scratch = study.stage_command(stages[2])[0]
    assert scratch[scratch.index("--cond") + 1] == "EXT-LS" and "sle_noise_steps=0" in scratch
    assert "sle_noise_steps=100000" not in scratch
    test = study.stage_command(stages[1])[0]
    assert test[test.index("-m") + 2].endswith("EV-LS/evolve")  # the learning test reads its own evolution
    # EV-LS lives a childhood, EXT-LS does not: costs in lane-steps at the paper's lengths.
    assert stages[0].cost == 5 * 50 * 100 * (150_000 + 6 * 100_000)
    assert stages[2].cost == 5 * 5 * 4 * 6 * 1_000_000


def test_unknown_row_is_refused(capsys):
    assert study.main(["--only", "EV-LS,XX"]) == 2
    assert "unknown row 'XX'" in capsys.readouterr().err


def test_traits_of_a_hand_made_genome():
    import numpy as np

    from imrl_jax import networks
    from imrl_jax.config import make_config

    config = make_config("skills", condition="LE-LS-P")
    genome = np.zeros(config.num_genes, np.float32)  # every parameter gene 0: u = 0.5 of its range
    values = dict(zip(networks.trait_names(config), np.asarray(networks.traits(config, genome))))
    assert values["eta_actor"] == pytest.approx(1e-2) and values["noise_std"] == pytest.approx(0.5)
    assert values["gamma"] == pytest.approx(1 - 10 ** -1.75) and values["initial_speed_bias"] == pytest.approx(2.0)
    config = make_config("skills", condition="LE-LS-N", num_experts=4)
    genome = np.zeros(config.num_genes, np.float32)
    genome[-4:] = [0.5, -0.2, 0.1, -0.9]  # the expression genes come last: experts 1 and 3 expressed
    assert np.asarray(networks.traits(config, genome)).tolist() == [2, 0, 1, 0, 0]
    assert networks.trait_names(make_config("skills", condition="LE-LS")) == ()


@pytest.mark.slow
def test_history_records_the_evolved_values_and_they_survive_a_resume(tmp_path):
    import csv

    import jax
    import numpy as np
    from helpers import evolve_args, read_population

    from imrl_jax import evolve, networks
    from imrl_jax.config import make_config

    out = str(tmp_path / "run")
    args = evolve_args("LE-LS-P", seeds=2, population=4, parents=2, task_steps=100, childhood_steps=100, bins=1)
    assert evolve.main([*args, "--generations", "2", "--out", out]) == 0
    with open(f"{out}/history.csv") as f:
        before = list(csv.DictReader(f))
    assert evolve.main(["--resume", "--out", out, "--generations", "3", "--quiet"]) == 0
    with open(f"{out}/history.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows[:4] == before  # the first generations' values came back from the checkpoint as written
    config = make_config("small", condition="LE-LS-P")
    arrays = read_population(out)
    values = np.asarray(jax.vmap(jax.vmap(lambda g: networks.traits(config, g)))(arrays["evaluated"]))
    best = arrays["fitness"].argmax(1)
    for s in range(2):
        row = rows[4 + s]
        assert row["generation"] == "2"
        for t, name in enumerate(networks.trait_names(config)):
            assert float(row[f"mean_{name}"]) == pytest.approx(values[s, :, t].mean(), rel=1e-5)
            assert float(row[f"best_{name}"]) == pytest.approx(values[s, best[s], t], rel=1e-5)
    assert os.path.getsize(f"{out}/traits.png") > 10_000


def test_record_traits_and_their_history_columns_by_hand():
    import numpy as np

    from imrl_jax import evolve
    from imrl_jax.checkpoint import empty_history

    traits = np.full((2, 1, 2, 2), np.nan, np.float32)
    values = np.asarray([[[1.0, 10.0], [3.0, 30.0], [2.0, 20.0]]])  # 1 seed x 3 individuals x 2 traits
    traits = evolve.record_traits(traits, 0, np.asarray([[0.1, 0.5, 0.2]]), values)
    np.testing.assert_allclose(traits[0, 0], [[2.0, 3.0], [20.0, 30.0]])  # (mean, the best's) per trait
    assert np.isnan(traits[1]).all()
    text = evolve.history_csv(empty_history(2, 1, 6), 1, [7], traits, ("a", "b"))
    header, row = text.splitlines()
    assert header.endswith(",mean_a,best_a,mean_b,best_b") and row.endswith(",2,3,20,30")
