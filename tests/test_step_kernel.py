"""step_kernel="auto", the default (issue 57): the Pallas kernel on a GPU where it implements the model, the XLA
step otherwise; resolved where a run is planned, recorded in config.json, kept by a resume, never part of a key."""

import json
import os

import jax
import pytest

from imrl_jax import conditions
from imrl_jax.commands import evolve
from imrl_jax.world import worlds
from imrl_jax.agent import kernel_choice
from imrl_jax.config import Config, make_config
from imrl_jax.runs.runspec import RunSpec
from attack import attack
from helpers import evolve_args, tiny_config

#: In the arena the kernel lives every condition; another world lives on the XLA step.
ON_KERNEL = conditions.NAMES
OFF_KERNEL = ("LE-LS", "EE-LS", "EE-ES", "SLE")


def _in_xland(config):
    return worlds.configure(config, "xland")


def test_auto_is_the_default_and_the_paper_preset_states_no_kernel():
    assert Config().step_kernel == "auto" and make_config("paper").step_kernel == "auto"


@pytest.mark.parametrize("condition", ON_KERNEL)
def test_auto_is_the_kernel_on_a_gpu_for_a_model_it_implements(condition):
    config, note = kernel_choice.resolve(make_config("small", condition=condition), "gpu")
    assert (config.step_kernel, note) == ("pallas", None)


@pytest.mark.parametrize("condition", OFF_KERNEL)
def test_auto_falls_back_to_xla_on_a_gpu_with_a_note_in_another_world(condition):
    config, note = kernel_choice.resolve(_in_xland(make_config("small", condition=condition)), "gpu")
    assert config.step_kernel == "xla"
    assert note == (f"note: step_kernel=auto: {condition} lives on the XLA step on this GPU, as the Pallas kernel "
                    f"does not implement world xland (the arena's only)")


@pytest.mark.parametrize("termination", ["period", "colour"])
def test_auto_is_the_kernel_for_the_selector_on_its_own_time_scale(termination):
    config = make_config("small", condition="LE-LS", selector_period=10, selector_termination=termination)
    assert kernel_choice.resolve(config, "gpu") == (config.replace(step_kernel="pallas"), None)


@pytest.mark.parametrize("backend", ["cpu", "tpu"])
def test_auto_is_xla_off_a_gpu_without_a_note(backend):
    assert kernel_choice.resolve(make_config("small", condition="LE-LS"), backend) == (
        make_config("small", condition="LE-LS", step_kernel="xla"), None)


@pytest.mark.parametrize("explicit", ["xla", "pallas"])
def test_an_explicit_kernel_is_kept_on_any_backend(explicit):
    config = make_config("small", condition="EE-LS", step_kernel=explicit)
    assert kernel_choice.resolve(config, "gpu") == (config, None) == kernel_choice.resolve(config, "cpu")


def test_the_kernel_is_not_part_of_a_run_key():
    config = make_config("paper", condition="LE-LS")
    keys = {RunSpec.make(config.replace(step_kernel=k), [0, 1]).key() for k in ("auto", "xla", "pallas")}
    assert len(keys) == 1


def test_a_config_recorded_before_the_field_is_the_xla_step():
    recorded = make_config("small", condition="EE-LS").to_dict()
    del recorded["step_kernel"]
    assert Config.from_dict(recorded).step_kernel == "xla"
    assert Config.from_dict({**recorded, "step_kernel": "pallas"}).step_kernel == "pallas"


def test_auto_on_cpu_is_the_xla_program():
    """Bitwise nothing changes on CPU: a life under "auto" is the same program as under "xla" (no compile)."""
    from imrl_jax.agent.lifetime import live

    assert jax.default_backend() == "cpu"
    programs = []
    for step_kernel in ("auto", "xla"):
        config = tiny_config("LE-LS", step_kernel=step_kernel)
        genome = jax.numpy.zeros((config.num_genes,))
        programs.append(str(jax.make_jaxpr(lambda k, g: live(k, config, config.learning_params(), g))(
            jax.random.key(0), genome)))
    assert programs[0] == programs[1]


def _plan(tmp_path, monkeypatch, backend, *argv):
    monkeypatch.setattr(kernel_choice, "default_backend", lambda: backend)
    outcome = attack(evolve.main, list(argv), str(tmp_path))
    assert outcome.code == 0 and outcome.planned and not outcome.changed, outcome.stderr
    return outcome


def test_evolve_records_the_resolved_kernel(tmp_path, monkeypatch):
    args = evolve_args("EE-LS", seeds=1, population=4, parents=2, generations=1, task_steps=200, bins=1)
    assert _plan(tmp_path, monkeypatch, "cpu", *args, "--out", "a").plan.config.step_kernel == "xla"
    assert _plan(tmp_path, monkeypatch, "gpu", *args, "--out", "a").plan.config.step_kernel == "pallas"
    fallback = _plan(tmp_path, monkeypatch, "gpu", *args[:-1], "--world", "xland", "--out", "b")
    assert fallback.plan.config.step_kernel == "xla"
    assert any("does not implement world xland" in note for note in fallback.plan.notes)


@pytest.mark.parametrize("recorded", ["xla", None])
def test_a_resumed_run_keeps_its_recorded_kernel(tmp_path, monkeypatch, recorded):
    """A run recorded with xla (or before the field) resumed on a GPU stays xla, unless --set chooses again."""
    run = tmp_path / "run"
    run.mkdir()
    config = make_config("small", condition="EE-LS", num_generations=2, step_kernel=recorded or "xla").to_dict()
    if recorded is None:
        del config["step_kernel"]
    (run / "config.json").write_text(json.dumps({"config": config, "seeds": [0]}))
    resume = ["--out", "run", "--resume", "--quiet"]
    assert _plan(tmp_path, monkeypatch, "gpu", *resume).plan.config.step_kernel == "xla"
    assert _plan(tmp_path, monkeypatch, "gpu", *resume, "--preset", "small").plan.config.step_kernel == "xla"
    chosen = _plan(tmp_path, monkeypatch, "gpu", *resume, "--set", "step_kernel=auto").plan.config
    assert chosen.step_kernel == "pallas"
    assert os.listdir(run) == ["config.json"]


def test_the_cuda_extra_is_jax_for_cuda_at_a_tested_version():
    """pip install -e ".[cuda]": JAX's CUDA 12 wheels, pinned, at or above the floor the suite declares."""
    import re
    import tomllib

    from packaging.version import Version

    from helpers import ROOT

    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        project = tomllib.load(f)["project"]
    (pin,) = project["optional-dependencies"]["cuda"]
    version = re.fullmatch(r"jax\[cuda12\]==([\d.]+)", pin).group(1)
    floor = next(d.split(">=")[1].split()[0] for d in project["dependencies"] if d.startswith("jax>="))
    assert Version(version) >= Version(floor)


def test_a_learning_test_chooses_its_kernel_for_this_machine(tmp_path, monkeypatch):
    """A test is computed anew: auto on a GPU, the fallback noted, unless --set step_kernel chooses."""
    from imrl_jax.commands import learning_test

    monkeypatch.setattr(kernel_choice, "default_backend", lambda: "gpu")
    argv = ["--cond", "SLE", "--tests", "1", "--task-steps", "400", "--bins", "4", "--steady-steps", "200",
            "--chunks", "1"]

    def planned(*more):
        outcome = attack(learning_test.main, [*argv, *more, "--out", "t"], str(tmp_path))
        assert outcome.code == 0 and outcome.planned and not outcome.changed, outcome.stderr
        return outcome.plan.tests[0]

    assert planned().config.step_kernel == "pallas"
    assert planned("--set", "step_kernel=xla").config.step_kernel == "xla"
    assert planned("--set", "selector_period=5").config.step_kernel == "pallas"  # the selector's options too
    elsewhere = planned("--world", "xland")
    assert elsewhere.config.step_kernel == "xla" and any("world xland" in n for n in elsewhere.notes)


@pytest.mark.parametrize("world, kernel", [("arena", "pallas"), ("xland", "xla")])
def test_a_sweep_records_the_resolved_kernel_in_every_point(tmp_path, monkeypatch, world, kernel):
    """A sweep's points differ in dynamic values only (one program): the base's choice is every point's."""
    args = evolve_args("EV-LS" if world == "arena" else "LE-LS", seeds=1, population=4, parents=2, generations=1,
                       task_steps=200, bins=1)[:-1]
    outcome = _plan(tmp_path, monkeypatch, "gpu", *args, "--world", world, "--sweep", "gamma=0.9,0.99", "--out", "s")
    assert outcome.plan.config.step_kernel == kernel
    assert {p.config.step_kernel for p in outcome.plan.points} == {kernel}
    assert any("does not implement world xland" in line for line in outcome.plan.lines) == (kernel == "xla")
