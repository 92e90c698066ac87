"""The future-work study's plan: each new row evolved (or tested from scratch) with its preset and overrides."""

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
