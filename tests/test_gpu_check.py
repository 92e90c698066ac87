"""``python -m imrl_jax.gpu_check``: its dry run end to end, failures kept to their piece, the budget, bad input."""

import json
import os

import jax
import numpy as np
import pytest

from imrl_jax import conditions as C
from imrl_jax.commands import gpu_check as G
from imrl_jax.commands import gpu_harness as H
from imrl_jax.commands import gpu_steps as S


def test_dry_run_checks_and_times_every_step(tmp_path):
    """At tiny sizes on CPU: every step runs, the lives agree, and the three files hold the figures."""
    import subprocess
    import sys

    from helpers import ROOT

    out = tmp_path / "check"
    # The command line in its own process with XLA's backend optimisations off: the dry run compiles some twenty
    # programs that each run in moments, and compares only lives (to 1e-10, or events exactly), not speeds.
    env = {**os.environ, "JAX_DISABLE_MOST_OPTIMIZATIONS": "1"}
    done = subprocess.run([sys.executable, "-m", "imrl_jax.gpu_check", "--out", str(out), "--dry"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    results = json.loads((out / "gpu_check.json").read_text())
    steps = {s["step"]: s for s in results["steps"]}
    assert list(steps) == [name for name, *_ in G.STEPS]
    assert all(s["status"] == "ok" for s in steps.values()), {n: s.get("failures") for n, s in steps.items()}
    assert results["machine"]["backend"] == jax.default_backend() and results["dry"] is True
    lives = steps["lives"]["rows"]
    assert [(r["condition"], r["preset"]) for r in lives] == [("EE-LS", "paper"), ("EE-LS", "paper+colour")]
    for row in lives:  # the selector's options too: on the kernel, against the reference
        assert row["pallas_vs_xla"]["events_equal"] and row["pallas_vs_reference"]["ok"]
        assert row["xla_vs_reference"]["max_weight_diff"] < 1e-10
    assert lives[0]["auto"] == ("pallas" if jax.default_backend() == "gpu" else "xla")  # step_kernel=auto's choice
    assert {r["kernel"]: r["reaches"] for r in steps["float32"]["rows"]} == {"xla": 2, "pallas": 2}
    assert {(r["kernel"], r["seeds"]) for r in steps["generation"]["rows"]} == {("xla", 2), ("pallas", 2)}
    for row in steps["life"]["rows"] + steps["generation"]["rows"] + steps["phases"]["rows"]:
        assert row["lane_steps_per_s"] > 0 and row["compile_s"] > 0, row
    # Only the phases of the checked conditions (EE-LS: the learning selector's adulthood), the XLA step and the
    # kernel observing either way (kernel_retina).
    assert {(r["phase"], r["kernel"], r.get("retina")) for r in steps["phases"]["rows"]} == {
        ("LE-LS/EE-LS adulthood", "xla", None), ("LE-LS/EE-LS adulthood", "pallas", "entries"),
        ("LE-LS/EE-LS adulthood", "pallas", "points")}
    counts = {}
    for kernel_row in (r for r in steps["phases"]["rows"] if r["kernel"] == "pallas"):  # its counted instructions
        assert kernel_row["warp_instructions_per_s"] == pytest.approx(kernel_row["lane_steps_per_s"]
                                                                      * kernel_row["warp_instructions"])
        counts[kernel_row["retina"]] = kernel_row["warp_instructions"]
    assert counts["entries"] - counts["points"] == 186 and counts["points"] > 500
    assert steps["sweep"]["points"] == 2 and len(steps["sweep"]["best_fitness"]) == 2
    assert steps["devices"]["devices"] == 1 and steps["devices"]["rows"] == []  # one device: nothing to shard
    # Every model's whole lives on the kernel (here the checked condition and its selector on its own time-scale).
    models = steps["models"]["rows"]
    assert [(r["condition"], r["options"], r["status"]) for r in models] == [("EE-LS", "", "ok"),
                                                                             ("EE-LS", "colour", "ok")]
    assert models[0]["over_first"] == 1.0 and models[1]["over_first"] > 0
    # The study: every distinct program of the claims map counted, --dry times the first (a sweep of two runs) and
    # the first kind of learning test; the estimate is then incomplete and the target not judged.
    study = steps["study"]
    programs = [r for r in study["rows"] if r["part"] == "evolution"]
    assert study["programs"] == len(programs) == len({(r["program"], r["seeds"]) for r in programs}) > 1
    assert study["runs"] == sum(len(r["runs"]) for r in programs) and len(programs[0]["runs"]) == 2
    timed = [r for r in study["rows"] if r["status"] == "ok"]
    assert [r["part"] for r in timed] == ["evolution", "test"] and timed[0]["timed_points"] == 2
    assert all(r["status"] == "skipped (dry)" for r in study["rows"] if r not in timed)
    assert timed[0]["generation_s"] > 0 and timed[1]["lane_steps_per_s"] > 0
    assert study["complete"] is False and study["meets_target"] is None and study["hours"] > 0
    text = (out / "gpu_check.txt").read_text()
    assert "done: 10 steps ok, failed: none, skipped: none" in text
    assert (out / "gpu_check.png").stat().st_size > 10_000


def _steps(log):
    def environment(check):
        return {}

    def broken(check):
        check.stage = "lowering"
        raise ValueError("Operand 18 of operation\nsecond line")

    def pieces(check):
        rows = []
        for kernel in ("xla", "pallas"):
            row = {"kernel": kernel, "lanes": 6}
            with check.piece(row, rows):
                check.stage = "compile"
                if kernel == "pallas":
                    raise RuntimeError("no Triton")
                row["status"] = "ok"
        log.append("pieces ran both kernels")
        return {"rows": rows}

    return (("environment", environment, 0), ("broken", broken, 0), ("pieces", pieces, 0))


def test_a_failure_is_kept_to_its_step_or_piece_and_the_check_goes_on(tmp_path):
    log = []
    results = G.run(str(tmp_path), 60, H.DRY, log=lambda line: None, steps=_steps(log))
    steps = {s["step"]: s for s in results["steps"]}
    assert steps["environment"]["status"] == "ok"
    assert (steps["broken"]["status"], steps["broken"]["stage"]) == ("failed", "lowering")
    assert steps["broken"]["error"] == "ValueError: Operand 18 of operation"  # one line
    assert log == ["pieces ran both kernels"]
    assert steps["pieces"]["status"] == "failed"
    assert steps["pieces"]["failures"] == ["pallas 6: compile: RuntimeError: no Triton"]
    assert steps["pieces"]["rows"][0]["status"] == "ok"
    assert results["summary"] == {"failed": ["broken", "pieces"], "skipped": []}
    written = json.loads((tmp_path / "gpu_check.json").read_text())
    assert written["summary"] == results["summary"]
    text = (tmp_path / "gpu_check.txt").read_text()
    assert "[broken] FAILED at lowering: ValueError: Operand 18 of operation" in text


def test_what_does_not_fit_the_budget_is_skipped_and_said(tmp_path):
    """At the real sizes (scale 1) a step that needs more than is left is skipped; the files are still written."""
    log = []
    steps = (("environment", lambda check: {}, 0), ("long", lambda check: log.append("ran") or {}, 120))
    results = G.run(str(tmp_path), 30, H.Sizes(), log=lambda line: None, steps=steps)
    long = results["steps"][1]
    assert log == [] and long["status"] == "skipped" and "about 120 s needed" in long["error"]
    assert results["summary"] == {"failed": [], "skipped": ["long"]}
    assert {p.name for p in tmp_path.iterdir()} == {"gpu_check.json", "gpu_check.txt"}  # no figure: nothing timed


def test_a_step_with_a_share_of_the_budget_stops_when_it_has_used_it(tmp_path, monkeypatch):
    check = H.Check(str(tmp_path), 100.0, H.Sizes(), log=lambda line: None)
    monkeypatch.setattr(check, "remaining", lambda: 90.0)
    assert check.share_left(S.LIVES_SHARE) == pytest.approx(55.0)  # 35 of the budget's 100 s from now


def test_the_devices_step_times_a_generation_sharded_over_every_device(tmp_path):
    """On 2 forced CPU devices: the generation of the most seeds on one device and on both, the kernel's lanes
    sharded, with the same fitness bit for bit; the speed-up recorded (not a speed here: --dry, the kernel
    interpreted)."""
    import subprocess
    import sys

    from helpers import ROOT, environment

    out = tmp_path / "check"
    env = {**environment(devices=2), "JAX_DISABLE_MOST_OPTIMIZATIONS": "1"}
    done = subprocess.run([sys.executable, "-m", "imrl_jax.gpu_check", "--out", str(out), "--dry", "--only",
                           "devices"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    steps = {s["step"]: s for s in json.loads((out / "gpu_check.json").read_text())["steps"]}
    sharded = steps["devices"]
    assert sharded["status"] == "ok" and sharded["devices"] == 2 and sharded["same_fitness"] is True
    assert [(r["devices"], r["seeds"], r["status"]) for r in sharded["rows"]] == [(1, 2, "ok"), (2, 2, "ok")]
    assert sharded["speedup"] > 0 and {r["kernel"] for r in sharded["rows"]} == {"pallas"}


@pytest.mark.slow  # every row's lives on both steps, the kernel interpreted: 3 min 30 s on 2 cores
def test_dry_lives_and_models_of_every_row(tmp_path):
    """``gpu_check --dry --only lives,models --conditions <every row>``: every condition of the table and its
    selector's options live on both steps as the reference does, and every one's whole lives run on the kernel."""
    import dataclasses

    sizes = dataclasses.replace(H.DRY, conditions=C.NAMES)
    steps = [step for step in G.STEPS if step[0] in ("lives", "models")]
    results = G.run(str(tmp_path), 900, sizes, log=lambda line: None, steps=steps)
    assert results["summary"] == {"failed": [], "skipped": []}
    lives = {(r["condition"], r["preset"]): r for r in results["steps"][0]["rows"]}
    assert {name for name, _ in lives} == set(C.NAMES)
    assert all(r["status"] == "ok" and r["kernels"] == ["xla", "pallas"] and r["pallas_vs_xla"]["events_equal"]
               for r in lives.values())
    assert ("LE-LS-2R", "paper+colour") in lives and ("SLE", "paper+colour") not in lives
    models = results["steps"][1]["rows"]
    assert [r["condition"] for r in models] == [*C.NAMES, "LE-LS"] and all(r["status"] == "ok" for r in models)


def test_life_cases_one_per_model_breadth_first(monkeypatch):
    """A preset that gives the same lives as one before it (Config.model_differences) is not checked again; the
    selector's options where a condition has a selector; every condition first, then the options, then the other
    presets (a budget that runs out cuts presets, not models); every case is on the kernel."""
    cases = S.life_cases(H.Sizes(conditions=("EE-ES", "EV-LS", "SLE"), option_conditions=None))
    names = [(name, preset) for name, preset, _, _ in cases]
    # EE-ES learns nothing: every preset lives the same. EV-LS: four models. SLE: one expert, nothing to choose.
    assert names == [("EE-ES", "paper"), ("EV-LS", "paper"), ("SLE", "paper"), ("EE-ES", "paper+period"),
                     ("EE-ES", "paper+colour"), ("EV-LS", "paper+period"), ("EV-LS", "paper+colour"),
                     ("EV-LS", "extension"), ("EV-LS", "faithful"), ("EV-LS", "skills"), ("SLE", "extension"),
                     ("SLE", "skills")]
    assert [reason for *_, reason in cases] == [None] * len(cases)
    colour = cases[4][2]
    assert (colour.selector_period, colour.selector_termination, colour.condition) == (4, "colour", "EE-ES")
    from imrl_jax.agent import kernel  # a model the kernel lacked would come after all the kernel's cases

    monkeypatch.setattr(kernel, "unsupported", lambda config: "lacks it" if config.condition == "EE-ES" else None)
    assert [name for name, *_ in S.life_cases(H.Sizes(conditions=("EE-ES", "EV-LS")))][-3:] == ["EE-ES"] * 3
    monkeypatch.undo()
    every = S.life_cases(H.Sizes())
    assert {name for name, *_ in every} == set(C.NAMES) and all(reason is None for *_, reason in every)
    # The real check's options: the conditions that hold every way an option meets learning, after every row.
    assert [(name, preset) for name, preset, *_ in every[len(C.NAMES):len(C.NAMES) + 6]] == [
        (name, f"paper+{option}") for name in ("LE-LS", "EE-ES", "EXT-LS") for option in ("period", "colour")]


def test_weights_excess_is_the_tolerance_test():
    """max |a - b| and how far it is past atol + rtol |b| (hand-computed)."""
    want = {"actor": np.array([1.0, -2.0]), "selector_critic": np.array([10.0])}
    got = {"actor": np.array([1.001, -2.0]), "selector_critic": np.array([10.0]), "evaluator": np.array([5.0])}
    largest, excess = S.weights_excess(got, want, rtol=1e-4, atol=1e-5)
    assert largest == pytest.approx(1e-3) and excess == pytest.approx(1e-3 - 1e-5 - 1e-4)
    assert S.weights_excess(got, want, rtol=1e-3, atol=1e-5)[1] <= 0


@pytest.mark.parametrize("args, message", [
    ([], "no GPU: jax"),
    (["--dry", "--budget-min", "0"], "--budget-min: must be above 0"),
    (["--dry", "--only", "lives,bogus"], "--only: unknown step 'bogus'"),
    (["--dry", "--conditions", "LE-LS,XX"], "--conditions: unknown condition 'XX'"),
], ids=["no-gpu", "budget", "step", "condition"])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "check"
    assert G.main(["--out", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {message}") and err.count("\n") == 1
    assert not out.exists()


def test_an_out_that_cannot_be_written_is_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert G.main(["--out", str(tmp_path / "file" / "check"), "--dry"]) == 2
    assert capsys.readouterr().err == f"error: --out: cannot write to {tmp_path / 'file' / 'check'} ({tmp_path / 'file'} is not a directory)\n"


def test_the_json_is_strict(tmp_path):
    check = H.Check(str(tmp_path), 10.0, H.DRY, log=lambda line: None)
    check.results["steps"].append({"step": "x", "rho": float("nan"), "rows": [{"v": np.float32("inf")}]})
    check.write()
    assert json.loads((tmp_path / "gpu_check.json").read_text())["steps"][0] == {"step": "x", "rho": None,
                                                                                  "rows": [{"v": None}]}


def test_an_earlier_check_is_not_overwritten(tmp_path, capsys):
    (tmp_path / "gpu_check.json").write_text("{}")
    assert G.main(["--out", str(tmp_path), "--dry"]) == 2
    assert "gpu_check.json exists" in capsys.readouterr().err
    assert (tmp_path / "gpu_check.json").read_text() == "{}" and len(os.listdir(tmp_path)) == 1
    assert G.main(["--out", "", "--dry"]) == 2


def test_the_study_counts_each_distinct_program_of_the_claims_map():
    """Every evolved row of the map in one run, rows of one run together, runs of one static part (and seed count)
    in one program: the programs' static parts differ, and a program's runs differ only in dynamic values."""
    from experiments.claims_study import SCREEN_TABLE
    from experiments.harness.table import evolution_spec
    from imrl_jax.commands import gpu_study
    from imrl_jax.runs import runspec
    from imrl_jax.evolution import sweeps

    programs = gpu_study.claims_programs()
    names = [name for p in programs for names, _ in p.runs for name in names]
    assert sorted(names) == sorted(row.name for row in SCREEN_TABLE.rows if row.evolved)
    assert len({(p.key, p.seeds) for p in programs}) == len(programs)
    spec = {row.name: evolution_spec(row, SCREEN_TABLE.scale_of(row)) for row in SCREEN_TABLE.rows if row.evolved}
    for p in programs:
        configs = [spec[names[0]].config for names, _ in p.runs]
        assert {gpu_study.program_key(c) for c in configs} == {p.key} and len({spec[n[0]].key() for n, _ in p.runs}) \
            == len(p.runs)
        first = runspec.model(configs[0])
        assert all({f for f, v in runspec.model(c).items() if first.get(f) != v} <= set(sweeps.DYNAMIC_FIELDS)
                   for c in configs)
        assert all(len(spec[n].seeds) == p.seeds and spec[n].key() == spec[names[0]].key() for names, _ in p.runs
                   for n in names)
    which = {name: p.key for p in programs for names, _ in p.runs for name in names}
    # the learned experts' initial speed is compiled in: each bias its own program; the extension's rules differ from
    # paper-selector's only in learning values: one sweep
    assert len({which[f"skills-bias{b} LE-LS"] for b in range(3)}) == 3
    assert which["extension LE-LS"] == which["paper-selector LE-LS"]
    assert len(programs[0].runs) > 1  # sweeps first


def test_the_map_hours_are_generations_times_a_generation_plus_tests_at_their_speed():
    """Made-up timings, the hours by hand: 100 x 2 s + 10 s and 50 x 0.5 s + 5 s of evolution; 6e9 lane-steps at
    1e9/s + 2 s of tests."""
    from imrl_jax.commands.gpu_study import extrapolate

    programs = [{"generations": 100, "generation_s": 2.0, "compile_s": 10.0},
                {"generations": 50, "generation_s": 0.5, "compile_s": 5.0}]
    tests = [{"lane_steps": 6e9, "lane_steps_per_s": 1e9, "compile_s": 2.0}]
    got = extrapolate(programs, tests)
    assert got["evolution_hours"] == pytest.approx((210 + 30) / 3600) and got["test_hours"] == pytest.approx(8 / 3600)
    assert got["hours"] == pytest.approx(248 / 3600) and got["complete"] and got["meets_target"] is True
    slow = extrapolate([{"generations": 100, "generation_s": 40.0, "compile_s": 0.0}], tests)
    assert slow["hours"] == pytest.approx((4000 + 8) / 3600) and slow["meets_target"] is False
    untimed = extrapolate(programs + [{"generations": 100, "status": "skipped (budget)"}], tests)
    assert untimed["hours"] == pytest.approx(got["hours"]) and not untimed["complete"]
    assert untimed["meets_target"] is None


def test_a_program_is_timed_at_a_fraction_when_a_whole_generation_would_not_fit(tmp_path, monkeypatch):
    """At 1e6 lane-steps/s a generation of 2 runs x 10 seeds x 50 of 750,000 steps takes 750 s; with 100 s left of
    the step's share for 2 programs, each may take 25 s timed (half for compiling): 1/30 of its lives."""
    from imrl_jax.commands import gpu_study
    from imrl_jax.config import make_config

    check = H.Check(str(tmp_path), 1000.0, H.Sizes(), log=lambda line: None)
    monkeypatch.setattr(check, "remaining", lambda: 300.0)
    program = gpu_study.Program("k", "LE-LS", make_config("paper", condition="LE-LS"), ((("a",), {}), (("b",), {})),
                                10, 100)
    assert gpu_study.fraction_for(check, program, 1e6, 200.0, 2) == pytest.approx(25 / 750)
    assert gpu_study.fraction_for(check, program, 3e7, 200.0, 2) == 1.0  # 25 s: whole
    assert gpu_study.fraction_for(check, program, None, 200.0, 2) == 1.0  # no speed yet: whole
    assert gpu_study.fraction_for(check, program, 1e4, 200.0, 2) == gpu_study.MIN_FRACTION
    config = gpu_study.sized(check, program.config, 25 / 750)
    assert (config.childhood_steps, config.task_steps) == (5000, 3300)  # whole bins of 100 steps
    config = gpu_study.sized(check, program.config, 0.0123)
    assert (config.childhood_steps, config.task_steps) == (1800, 1200)  # 1,845 and 1,230 to whole bins


def test_the_kernels_work_per_step_is_counted_from_its_code_and_the_sizes():
    """The networks' multiply-adds of LE-LS's childhood at K = 3, n + 1 = 37, by hand: forward selector 111, actor
    222, reinforcer 111, evaluator 222; expert traces 111, updates 333; critic 74, selector traces 148, updates
    148. The traced loop body makes as many matrix-vector products (reductions of a Kp x N matrix's rows) as the
    count's forward terms, and reads the draws alone from global memory each step (float32 u, and z when noisy)."""
    from imrl_jax import conditions as C
    from imrl_jax.agent import kernel_work as W
    from imrl_jax.config import make_config
    from imrl_jax.agent.state import childhood_phase

    config = make_config("paper", condition="LE-LS")
    childhood = childhood_phase(config)
    assert sum(W.network_macs(config, childhood).values()) == 1480
    assert sum(W.network_macs(config, C.ADULT_LEARNING_SELECTOR).values()) == 111 + 222 + 74 + 148 + 148
    assert sum(W.network_macs(config, C.ADULT_EVOLVED_SELECTOR).values()) == 333
    assert sum(W.network_macs(config, childhood, padded=True).values()) == 6 * 256 + 3 * 64 + 3 * 256 + 128 + 2 * 320
    four = config.replace(num_experts=4)  # 11 K x (n+1) terms and 7 of n+1: 1480 = 11 x 111 + 7 x 37 at K = 3
    assert sum(W.network_macs(four, childhood).values()) == 11 * 4 * 37 + 7 * 37  # 11 matrix terms, 7 vector ones
    for phase, products, dots, read in ((childhood, 6, 2, 12), (C.ADULT_LEARNING_SELECTOR, 3, 2, 4),
                                        (C.ADULT_EVOLVED_SELECTOR, 3, 0, 4)):
        work = W.loop_work(config, phase)
        forward = [m for name, m in W.network_macs(config, phase).items() if "forward" in name or "V(" in name]
        assert sum(forward) == (products * 3 + dots) * 37
        assert work["global_read_bytes"] == read and work["flops"] > 2 * sum(W.network_macs(config, phase,
                                                                                             padded=True).values())
        assert work["warp_instructions"] > 0
    assert W.loop_work(config, childhood)["warp_instructions"] > W.loop_work(config, C.ADULT_EVOLVED_SELECTOR)[
        "warp_instructions"]


def test_the_retina_per_point_would_spare_most_of_observes_instructions():
    """The planned variant's count: observe on 16 points and broadcast to the 64 entries takes about half the warp
    instructions of today's 64 entries, and today's is most of an EE-ES step's (PERFORMANCE.md's 392 of 688)."""
    from imrl_jax import conditions as C
    from imrl_jax.agent import kernel_work as W
    from imrl_jax.config import make_config

    config = make_config("paper", condition="LE-LS")
    today, planned = W.observe_work(config), W.observe_work(config, points=True)
    # the same arithmetic on 64 entries rather than 16 points, the bias added to the 64 entries in both
    assert today["flops"] - 64 == 4 * (planned["flops"] - 64)
    assert today["warp_instructions"] > 1.8 * planned["warp_instructions"]
    assert today["warp_instructions"] > W.loop_work(config, C.ADULT_EVOLVED_SELECTOR)["warp_instructions"] / 2
