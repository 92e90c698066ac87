"""The search study's plan: each strategy evolves each condition under skills, then its best are tested."""

from experiments import search as study


def test_plan_evolves_each_row_with_its_strategy_and_tests_its_own_run():
    rows = [study.BY_NAME["snes-EE-ES"], study.BY_NAME["sep_cma_es-LE-LS"]]
    stages = study.plan(rows)
    assert [s.name for s in stages] == ["evolve snes-EE-ES", "learning test snes-EE-ES",
                                        "evolve sep_cma_es-LE-LS", "learning test sep_cma_es-LE-LS"]
    evolve = study.stage_command(stages[2])[0]
    assert evolve[evolve.index("--strategy") + 1] == "sep_cma_es" and evolve[evolve.index("--cond") + 1] == "LE-LS"
    assert evolve[evolve.index("--preset") + 1] == "skills" and evolve[evolve.index("--seeds") + 1] == "5"
    test = study.stage_command(stages[1])[0]
    assert test[test.index("-m") + 2].endswith("snes/EE-ES/evolve")
    assert stages[0].cost == 5 * 50 * 100 * 6 * 100_000 and stages[2].cost == 5 * 50 * 100 * (150_000 + 600_000)


def test_unknown_rows_are_refused_and_a_strategy_selects_its_rows(capsys):
    assert study.main(["--only", "snes,cma"]) == 2
    assert "unknown strategy or row 'cma'" in capsys.readouterr().err
    assert study.main(["--only", "snes", "--list"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 6 and all("snes" in line for line in printed)
