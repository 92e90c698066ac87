"""Another world's speed (issue #56): an agent's phases in it against the world stepped alone, in lane-steps per second.

    python -m imrl_jax.bench --world xland [--world-set FIELD=VALUE] [--only-world] [--lanes 50,300] [--steps 1000]

For each lane count (one individual per lane): LE-LS childhood in the world (the open room, intrinsic rewards) and
the LE-LS/EE-LS adulthood (task 1, the learning selector), each against the same environment stepped alone for as
many steps with uniformly random actions (observe, then transition, every step: the world's part of the agent's
step). The two programs' timed runs alternate, so both see the same machine; ``ratio`` is the world alone's rate over
the agent's: how many times slower an agent's step is than the world's own (what its networks and learning cost).
"""

from __future__ import annotations

import statistics
import time

import jax
import jax.numpy as jnp

from imrl_jax.agent import lifetime as L
from imrl_jax.agent.state import childhood_phase, init_state
from imrl_jax.commands.bench_lanes import Program, alternate, lane_inputs
from imrl_jax.config import Config, make_config
from imrl_jax.world import worlds
from imrl_jax.world.base import DISCRETE

#: (name, whether the phase is an adult task): LE-LS's childhood and its adulthood (LE-LS/EE-LS's learning selector)
WORLD_PHASES = (("LE-LS childhood", False), ("LE-LS/EE-LS adulthood", True))


def base_config(steps: int) -> Config:
    """LE-LS under the paper's preset with phases of ``steps`` steps, in the arena (move it with worlds.configure)."""
    return make_config("paper", condition="LE-LS", childhood_steps=steps, task_steps=steps, num_bins=1,
                       step_kernel="xla")


def _phase_setup(config: Config, adult: bool):
    """The phase, its environment, its task's params and the start of a lane (from its key)."""
    world, dtype = worlds.world_of(config), jnp.float32
    phase = config.spec.adult if adult else childhood_phase(config)
    env = world.make_env(config, phase.has_target, phase.respawn)
    task = world.task(config, 0, dtype) if adult else world.childhood_task(config, dtype)
    return phase, env, task, lambda key: env.reset(key, task, dtype)


def agent_program(config: Config, adult: bool, lanes: int, steps: int) -> Program:
    """The agent's phase (childhood, or task 1 of adulthood) for ``steps`` steps on ``lanes`` lanes."""
    phase, _, task, start = _phase_setup(config, adult)
    params = config.learning_params()

    def lane(key, genome):
        agent = L.with_params(L.decode(config, genome), params)
        if adult:
            state, phase_steps = L.task_start(config, agent, 0), config.adult_noise_steps
        else:
            state, phase_steps = init_state(config, agent, start(jax.random.fold_in(key, 1))), steps
        _, curves = L.run_phase(key, config, phase, params, task, state, steps, phase_steps=phase_steps)
        return curves.reaches, curves.selections

    return Program(jax.jit(jax.vmap(lane)), lane_inputs(config, lanes), lanes * steps, config)


def world_program(config: Config, adult: bool, lanes: int, steps: int) -> Program:
    """The same environment stepped alone for ``steps`` steps on ``lanes`` lanes, each step's action uniformly random.

    Every step observes (as the agent's step does; the observations are summed, so that none is left uncomputed)
    and transitions; returns the final states, the summed observations and the reaches."""
    world = worlds.world_of(config)
    _, env, task, start = _phase_setup(config, adult)
    actions = world.actions(config)

    def lane(key, genome):
        del genome  # the lanes' inputs are the agent program's: the world alone needs only the key
        k_start, k_action, k_spawn = jax.random.split(key, 3)
        if actions.kind == DISCRETE:
            chosen = jax.random.randint(k_action, (steps,), 0, actions.size, jnp.int32)
        else:
            chosen = jax.random.uniform(k_action, (steps, actions.size))
        spawn = jax.random.uniform(k_spawn, (steps, world.num_spawn_draws))
        state = start(k_start)

        def one_step(carry, draws):
            state, seen, reaches = carry
            seen = seen + env.observe(state).astype(seen.dtype)
            state, events = env.transition(state, draws[0], task, draws[1])
            return (state, seen, reaches + events.reached), None

        carry = (state, jnp.zeros((world.num_inputs(config),), jnp.float32), jnp.int32(0))
        return jax.lax.scan(one_step, carry, (chosen, spawn), unroll=config.scan_unroll)[0]

    return Program(jax.jit(jax.vmap(lane)), lane_inputs(config, lanes), lanes * steps, config)


def _compiled(program: Program):
    start = time.perf_counter()
    compiled = program.fn.lower(*program.args).compile()
    seconds = time.perf_counter() - start
    jax.block_until_ready(compiled(*program.args))  # the untimed first run
    return compiled, seconds


def bench_pair(config: Config, adult: bool, lanes: int, steps: int, repeats: int) -> dict:
    """The agent's phase and the world alone on the same lanes and steps, their timed runs alternating."""
    programs = {"agent": agent_program(config, adult, lanes, steps), "world": world_program(config, adult, lanes, steps)}
    compiled = {name: _compiled(program) for name, program in programs.items()}
    times = alternate({name: (compiled[name][0], program.args) for name, program in programs.items()}, repeats)
    row = {"lanes": lanes, "steps": steps}
    for name, program in programs.items():
        row[f"{name}_lane_steps_per_s"] = program.lane_steps / statistics.median(times[name])
        row[f"{name}_best_lane_steps_per_s"] = program.lane_steps / min(times[name])
        row[f"{name}_compile_s"] = compiled[name][1]
    row["ratio"] = row["world_lane_steps_per_s"] / row["agent_lane_steps_per_s"]
    return row


def run(config: Config, lane_counts, repeats: int, log=print) -> dict:
    """The world section of the benchmark for ``config``'s world (phases of ``config.task_steps`` steps)."""
    world = worlds.world_of(config)
    steps = config.task_steps
    section = {"name": config.world, "settings": dict(config.world_settings), "inputs": world.num_inputs(config),
               "actions": world.actions(config).size, "steps": steps, "repeats": repeats, "rows": []}
    settings = "".join(f" {name}={value}" for name, value in section["settings"].items())
    log(f"world {config.world}{settings}: {section['inputs']} inputs, {section['actions']} actions; "
        f"{steps:,} steps, medians of {repeats} alternating runs")
    log(f"{'phase':24s} {'lanes':>6s} {'agent lane-steps/s':>19s} {'world alone':>14s} {'ratio':>7s} "
        f"{'compile s':>10s}")
    for name, adult in WORLD_PHASES:
        for lanes in lane_counts:
            row = {"phase": name, **bench_pair(config, adult, lanes, steps, repeats)}
            section["rows"].append(row)
            log(f"{name:24s} {lanes:6d} {row['agent_lane_steps_per_s']:19,.0f} {row['world_lane_steps_per_s']:14,.0f} "
                f"{row['ratio']:6.1f}x {row['agent_compile_s']:5.1f}+{row['world_compile_s']:.1f}")
    return section
