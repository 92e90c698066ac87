"""``gpu_check``'s steps, each a function of the running :class:`~imrl_jax.commands.gpu_harness.Check` that returns
its figures: the machine (``environment``), short lives against the NumPy reference and between the kernels
(``lives``), the float32 adult phase (``float32``), whole lives (``life``), generations (``generation``), ``evolve
--sweep``'s program (``sweep``) and every phase of the benchmark (``phases``). The ``study`` step is
:mod:`imrl_jax.commands.gpu_study`'s.
"""

from __future__ import annotations

import contextlib
import os
import platform
import time

import numpy as np

from imrl_jax.commands.gpu_harness import (KERNELS, Check, Sizes, compile_once, compile_program, fastest_kernel,
                                           float64, program_bytes, timed)
from imrl_jax.commands.gpu_study import program_key

#: The CPU tests' tolerances: float64 lives against the reference (tests/test_reference.py), the kernel
#: against the XLA step (tests/test_kernel.py), the float32 adult phase against the reference.
TOLERANCES = {"reference": dict(rtol=1e-8, atol=1e-10), "kernels": dict(rtol=1e-9, atol=1e-9),
              "float32": dict(rtol=1e-4, atol=1e-5), "float32_pose_cm": 1e-3}


def environment(check: Check) -> dict:
    """The device, its memory and the versions of everything the engine uses."""
    import jax

    from imrl_jax.runs.checkpoint import package_versions

    check.stage = "api"
    device = jax.devices()[0]
    versions = package_versions(("jax", "jaxlib", "numpy", "optax", "orbax-checkpoint", "matplotlib", "brax", "evosax",
                                 "triton"))
    stats = device_memory = None
    with contextlib.suppress(Exception):
        stats = device.memory_stats() or {}
        device_memory = stats.get("bytes_limit")
    info = {"backend": jax.default_backend(), "device": getattr(device, "device_kind", str(device)),
            "num_devices": len(jax.devices()), "device_memory_bytes": device_memory, "cpu_count": os.cpu_count(),
            "machine": platform.machine(), "python": platform.python_version(), "versions": versions}
    with contextlib.suppress(Exception):
        info["environment"] = jax.print_environment_info(return_string=True)
    check.results["machine"] = info
    check.say(f"  {info['device']} x {info['num_devices']} ({info['backend']}), jax {versions['jax']}, "
              f"jaxlib {versions['jaxlib']}, python {info['python']}; device memory {device_memory}")
    return {}


def life_cases(sizes: Sizes):
    """(condition, preset, config, why the kernel lacks it or None) of every condition under every preset that makes
    another model (``Config.model_differences``), and under the first preset with each of the selector's options
    (``Sizes.selector_options``: "paper+colour") where its selector chooses (``Sizes.option_conditions``). Breadth
    first, so that a budget that runs out leaves the later presets unchecked rather than whole models: every
    condition under the first preset, then the options, then the other presets; the kernel's cases before the XLA
    step's alone."""
    from imrl_jax import conditions
    from imrl_jax.agent import kernel
    from imrl_jax.config import make_config

    childhood, task, bins = sizes.life_steps
    firsts, options, others = [], [], []  # the rounds, breadth first
    for name in sizes.conditions or conditions.NAMES:
        seen = []
        for preset in sizes.presets:
            config = make_config(preset, condition=name, childhood_steps=childhood, task_steps=task, num_bins=bins,
                                 target_radius=sizes.life_target_radius)
            if any(not config.model_differences(other) for other in seen):
                continue  # the same lives as a preset before it
            seen.append(config)
            (others if seen[1:] else firsts).append((name, preset, config, kernel.unsupported(config)))
        chooses = not conditions.get(name).single_expert
        if chooses and (sizes.option_conditions is None or name in sizes.option_conditions):
            for option, fields in sizes.selector_options:
                config = seen[0].replace(**dict(fields))
                options.append((name, f"{sizes.presets[0]}+{option}", config, kernel.unsupported(config)))
    # The kernel's cases first (a stable sort): the XLA-only ones check what the CPU tests check already.
    return sorted(firsts + options + others, key=lambda case: case[3] is not None)


def weights_excess(got, want: dict, rtol: float, atol: float) -> tuple[float, float]:
    """(max |got - want|, max of |got - want| - (atol + rtol |want|)) over the networks both have (ok: second <= 0)."""
    from imrl_jax.agent.reference import WEIGHT_KEYS

    largest, excess = 0.0, -np.inf
    for name in WEIGHT_KEYS:
        value = getattr(got, name) if not isinstance(got, dict) else got.get(name)
        if value is None or name not in want:
            continue
        diff = np.abs(np.asarray(value, np.float64) - np.asarray(want[name], np.float64))
        largest = max(largest, float(diff.max(initial=0.0)))
        excess = max(excess, float((diff - atol - rtol * np.abs(np.asarray(want[name], np.float64))).max(initial=-1)))
    return largest, excess


def compare_with_reference(life, ref: dict, num_tasks: int, tolerance: dict) -> dict:
    """A JAX life against the reference's: reaches equal, weights after childhood and every task within tolerance."""
    import jax

    reaches_equal = bool(np.array_equal(np.asarray(life.reaches), ref["reaches"]))
    largest, excess = weights_excess(life.agent, ref["childhood_weights"], **tolerance)
    for t in range(num_tasks):
        task_largest, task_excess = weights_excess(jax.tree.map(lambda x: x[t], life.adult_agents),
                                                   ref["task_weights"][t], **tolerance)
        largest, excess = max(largest, task_largest), max(excess, task_excess)
    return {"ok": reaches_equal and excess <= 0, "reaches_equal": reaches_equal, "max_weight_diff": largest,
            "reaches": int(np.sum(ref["reaches"]))}


def compare_kernels(pallas, xla, tolerance: dict) -> dict:
    """The kernel's life against the XLA step's: every event count equal, weights within tolerance."""
    events = ("reaches", "timeouts", "reward_curve", "adult_selections", "childhood_selections")
    equal = all(np.array_equal(np.asarray(getattr(pallas, n)), np.asarray(getattr(xla, n))) for n in events)
    largest, excess = 0.0, -np.inf
    for name in ("agent", "adult_agents"):
        want = {k: v for k, v in getattr(xla, name)._asdict().items() if v is not None}
        part_largest, part_excess = weights_excess(getattr(pallas, name), want, **tolerance)
        largest, excess = max(largest, part_largest), max(excess, part_excess)
    return {"ok": equal and excess <= 0, "events_equal": equal, "max_weight_diff": largest}


#: The share of the budget the ``lives`` step may use, so that the speed steps after it get the rest.
LIVES_SHARE = 0.35


def lives(check: Check) -> dict:
    """Short float64 lives of every case, XLA and Pallas, against the reference and each other."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent import kernel_choice, lifetime, reference
    from imrl_jax.config import Config, LearningParams

    rows, programs = [], {}
    stop = check.share_left(LIVES_SHARE)
    for name, preset, config, reason in life_cases(check.sizes):
        row = {"condition": name, "preset": preset, "kernels": list(KERNELS if reason is None else ("xla",)),
               "auto": kernel_choice.chosen(config)}  # what the default lives it with on this machine
        if reason:
            row["pallas"] = reason
        if check.remaining() < stop and check.sizes.scale:
            rows.append({**row, "status": "skipped (the step's share of the budget)"})
            continue
        with check.piece(row, rows), float64():
            check.stage = "api"
            key = jax.random.key(11)
            genome = jax.random.uniform(jax.random.key(12), (config.num_genes,), jnp.float64, -1.0, 1.0)
            params = jax.tree.map(lambda v: jnp.asarray(v, jnp.float64), config.learning_params())
            # Presets that differ only in learning values share one program (the values are its arguments).
            static = config.replace(**dict(zip(LearningParams._fields, Config().learning_params())))
            got = {}
            for kernel in row["kernels"]:
                program = static.replace(step_kernel=kernel)
                if program not in programs:
                    fn = lambda k, p, g, c=program: lifetime.live(k, c, p, g)  # noqa: E731
                    programs[program] = compile_program(check, fn, key, params, genome)
                executable, compile_s = programs[program]
                check.stage = "run"
                got[kernel] = jax.block_until_ready(executable(key, params, genome))
                row[f"{kernel}_compile_s"] = round(compile_s, 2)
            check.stage = "numbers"
            ref = reference.live_with(config, genome, lifetime.life_draws(key, config, jnp.float64))
            for kernel in got:
                row[f"{kernel}_vs_reference"] = compare_with_reference(got[kernel], ref, config.num_tasks,
                                                                       TOLERANCES["reference"])
            if len(got) == 2:
                row["pallas_vs_xla"] = compare_kernels(got["pallas"], got["xla"], TOLERANCES["kernels"])
            checks = {k: v for k, v in row.items() if isinstance(v, dict)}
            row["status"] = "ok" if all(v["ok"] for v in checks.values()) else "failed"
            if row["status"] == "failed":
                row["error"] = "outside tolerance: " + ", ".join(k for k, v in checks.items() if not v["ok"])
            check.say(f"  {name:10s} {preset:9s} {row['status']:6s} reaches {ref['reaches'].sum():4d}; "
                      + ", ".join(f"{k} {v['max_weight_diff']:.1e}" for k, v in checks.items()))
    return {"rows": rows}


def float32_phase(check: Check) -> dict:
    """The float32 CPU test's adult phase (EE-LS, hand-made experts, one short task) on both kernels."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent import lifetime as L
    from imrl_jax.agent import reference
    from imrl_jax.config import Task, make_config
    from imrl_jax.agent.networks import decode
    from imrl_jax.agent.state import draw_many
    from imrl_jax.world.env import at

    steps = check.sizes.float32_steps
    config = make_config("paper", condition="EE-LS", tasks=(Task(**reference.SHORT_TASK_FIELDS),), task_steps=steps,
                         num_bins=1)
    check.stage = "api"
    agent = decode(config, jnp.zeros((config.num_genes,)))._replace(
        actor=jnp.asarray(reference.hand_experts(config.num_inputs + 1), jnp.float32))
    task, key, params = L.task_spec(config, 0), jax.random.key(0), config.learning_params()
    state = L.init_state(config, agent, at(task.start))
    draws = draw_many(key, steps, config.draw_block)
    weights = {k: np.asarray(v, np.float64) for k, v in agent._asdict().items() if v is not None}
    ref = reference.run_phase(config, "adult-ls", weights, (*reference.SHORT_TASK_FIELDS["start"], 0.0),
                              np.asarray(draws.u, np.float64), np.asarray(draws.z, np.float64), task=0)
    rows, want = [], int(ref["reached"].sum())
    for kernel in KERNELS:
        row = {"kernel": kernel, "steps": steps, "reference_reaches": want}
        with check.piece(row, rows):
            c = config.replace(step_kernel=kernel)
            fn = lambda k, p, s, c=c: L.run_phase(k, c, c.spec.adult, p, task, s, steps)  # noqa: E731
            executable, _ = compile_program(check, fn, key, params, state)
            final, curves = jax.block_until_ready(executable(key, params, state))
            check.stage = "numbers"
            pose = np.asarray(final.world.pose.pos, np.float64)
            largest, excess = weights_excess(final.agent, ref["weights"], **TOLERANCES["float32"])
            row.update(reaches=int(curves.reaches.sum()), max_weight_diff=largest,
                       pose_diff_cm=float(np.abs(pose - [ref["x"][-1], ref["y"][-1]]).max()))
            ok = row["reaches"] == want and row["pose_diff_cm"] <= TOLERANCES["float32_pose_cm"] and excess <= 0
            row["status"] = "ok" if ok else "failed"
            if not ok:
                row["error"] = "outside the float32 test's tolerance"
            check.say(f"  float32 {kernel:6s} reaches {row['reaches']} (reference {want}), pose "
                      f"{row['pose_diff_cm']:.1e} cm, weights {largest:.1e}: {row['status']}")
    return {"rows": rows}


def whole_lives(check: Check) -> dict:
    """Whole LE-LS lives (bench's headline) at every lane count, both kernels."""
    from imrl_jax.commands import bench

    rows, last = [], {}
    for kernel in KERNELS:
        for lanes in check.sizes.lanes:
            row = {"kernel": kernel, "lanes": lanes}
            # At most in proportion to the lanes (a first run, then the repeats when it is short).
            if not check.fits(15 + last.get(kernel, 1.0) * (1 + check.sizes.repeats) * lanes / last.get(
                    (kernel, "lanes"), lanes)):
                rows.append({**row, "status": "skipped (budget)"})
                continue
            with check.piece(row, rows):
                check.stage = "api"
                program = bench.lifetime_program(lanes, check.sizes.life_task_steps, step_kernel=kernel)
                executable, compile_s = compile_program(check, program.fn, *program.args)
                seconds, shortest = timed(executable, program.args, check.sizes.repeats)
                individuals = program.args[2].shape[0]
                row.update(lanes=individuals * program.config.num_tasks, individuals=individuals,
                           childhood_steps=program.config.childhood_steps, task_steps=program.config.task_steps,
                           compile_s=compile_s, seconds=seconds, lane_steps_per_s=program.lane_steps / seconds,
                           best_lane_steps_per_s=program.lane_steps / shortest,
                           program_bytes=program_bytes(executable), status="ok")
                last.update({kernel: seconds, (kernel, "lanes"): lanes})
                check.say(f"  life {kernel:6s} {row['lanes']:8,d} lanes: {row['lane_steps_per_s']:14,.0f} "
                          f"lane-steps/s, compile {compile_s:5.1f} s, {seconds:.3f} s a life")
    return {"rows": rows}


def generation_inputs(config, num_seeds: int):
    """The keys, learning values, populations and index of generation 0 of seeds 0..num_seeds-1."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.evolution.ga import init_population

    seeds = jax.vmap(jax.random.key)(jnp.arange(num_seeds, dtype=jnp.uint32))
    populations = jax.vmap(lambda k: init_population(jax.random.fold_in(k, 0), config))(seeds)
    keys = jax.vmap(lambda k: jax.random.fold_in(k, 1))(seeds)
    return keys, config.learning_params(), populations, jnp.int32(0)


def generations(check: Check) -> dict:
    """One paper-scale generation (LE-LS; compilation apart) per kernel and seed count."""
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.evolution.ga import make_generation

    rows, last = [], {}
    for seeds in check.sizes.generation_seeds:
        for kernel in reversed(KERNELS):  # the kernel first: the XLA step's generation may take a minute
            row = {"kernel": kernel, "seeds": seeds}
            # A generation's time grows with the seeds at most in proportion: the last one bounds this one.
            if not check.fits(30 + last.get(kernel, 30) * seeds / last.get((kernel, "seeds"), seeds)):
                rows.append({**row, "status": "skipped (budget)"})
                continue
            with check.piece(row, rows):
                check.stage = "api"
                config = make_config("paper", condition=check.sizes.generation_condition, step_kernel=kernel,
                                     **dict(check.sizes.generation_sizes))
                args = generation_inputs(config, seeds)
                executable, compile_s = compile_program(check, make_generation(config), *args)
                start = time.perf_counter()
                _, stats = jax.block_until_ready(executable(*args))
                seconds = time.perf_counter() - start
                individuals = seeds * config.population_size
                row.update(individuals=individuals, compile_s=compile_s, seconds=seconds,
                           lane_steps_per_s=individuals * config.lifetime_steps / seconds,
                           evolution_minutes=seconds * config.num_generations / 60,
                           best_fitness=float(np.asarray(stats.fitness).max()),  # generation 0's best noisy life
                           num_generations=config.num_generations, status="ok")
                last.update({kernel: seconds, (kernel, "seeds"): seeds})
                check.say(f"  generation {kernel:6s} {seeds:3d} seeds: {seconds:7.2f} s (compile {compile_s:.1f} s), "
                          f"{config.num_generations} generations {row['evolution_minutes']:.1f} min")
    return {"rows": rows}


def devices(check: Check) -> dict:
    """One paper-scale generation of the most seeds on the kernel on every local device (its lanes under ``shard_map``,
    :func:`imrl_jax.evolution.search.shard_lanes`) against the same generation on one: seconds, the speed-up, and
    whether the fitness is the same (it must be, bit for bit). Nothing to time on one device."""
    import jax

    from imrl_jax.config import make_config
    from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
    from imrl_jax.evolution.ga import make_generation
    from imrl_jax.evolution.search import evolution_keys
    from imrl_jax.runs.run_state import initial_state

    count = len(jax.devices())
    if count < 2:
        check.say(f"  {count} device: nothing to shard")
        return {"devices": count, "rows": []}
    kernel, seeds = "pallas", max(check.sizes.generation_seeds)  # the kernel's lanes are what shard_map splits
    config = make_config("paper", condition=check.sizes.generation_condition, step_kernel=kernel,
                         **dict(check.sizes.generation_sizes))
    rows, fitness = [], {}
    for used in (1, count):
        row = {"kernel": kernel, "seeds": seeds, "devices": used}
        if not check.fits(60):
            rows.append({**row, "status": "skipped (budget)"})
            continue
        with check.piece(row, rows):
            check.stage = "api"
            mesh = make_mesh(used)
            sharding = population_sharding(mesh, seeds, config.population_size)
            state = initial_state(config, list(range(seeds)), sharding)
            args = (to_global(evolution_keys(state.key_data), replicated(mesh)), config.learning_params(),
                    state.populations, 0)
            executable, compile_s = compile_program(check, make_generation(config, sharding), *args)
            start = time.perf_counter()
            _, stats = jax.block_until_ready(executable(*args))
            seconds = time.perf_counter() - start
            fitness[used] = np.asarray(stats.fitness)
            individuals = seeds * config.population_size
            row.update(individuals=individuals, compile_s=compile_s, seconds=seconds,
                       lane_steps_per_s=individuals * config.lifetime_steps / seconds, status="ok")
            check.say(f"  generation {kernel:6s} {seeds:3d} seeds on {used} device(s): {seconds:7.2f} s "
                      f"(compile {compile_s:.1f} s)")
    done = {r["devices"]: r for r in rows if r.get("status") == "ok"}
    result = {"devices": count, "rows": rows}
    if len(done) == 2:
        result.update(speedup=done[1]["seconds"] / done[count]["seconds"],
                      same_fitness=bool(np.array_equal(fitness[1], fitness[count])))
        check.say(f"  {count} devices: {result['speedup']:.2f}x one; the same fitness: {result['same_fitness']}")
        if not result["same_fitness"]:  # the step fails, its figures kept
            done[count].update(status="failed", stage="numbers",
                               error=f"another fitness on {count} devices than on one")
    return result


def sweep(check: Check) -> dict:
    """One generation of ``evolve --sweep``'s program (every point and seed in one batch), with the fastest kernel,
    against the generation of as many seeds of a single run timed before it (the ratio: at most the points)."""
    import itertools

    import jax

    from imrl_jax.commands import evolve_sweep
    from imrl_jax.config import make_config
    from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global
    from imrl_jax.evolution.search import evolution_keys
    from imrl_jax.runs.run_state import initial_state

    kernel = fastest_kernel(check)
    check.stage = "api"
    config = make_config("paper", condition=check.sizes.generation_condition, step_kernel=kernel,
                         **dict(check.sizes.generation_sizes))
    names, values = zip(*check.sizes.sweep)
    settings = [dict(zip(names, combo)) for combo in itertools.product(*values)]
    seeds = list(range(check.sizes.sweep_seeds))
    points = evolve_sweep.make_points(config, seeds, settings)
    mesh = make_mesh()
    sharding = population_sharding(mesh, len(points) * len(seeds), config.population_size)
    state = initial_state(config, seeds, population_sharding(mesh, len(seeds), config.population_size))
    keys = to_global(evolution_keys(np.tile(state.key_data, (len(points), 1))), replicated(mesh))
    params, ga = evolve_sweep.batched_values(points, len(seeds))
    populations = to_global(np.tile(np.asarray(state.populations), (len(points), 1, 1)), sharding)
    step = evolve_sweep.make_sweep_step(config, sharding)
    key = ("sweep", program_key(config), kernel, len(points), len(seeds))
    executable, compile_s = compile_once(check, key, step, keys, params, ga, populations, 0)
    start = time.perf_counter()
    _, stats = jax.block_until_ready(executable(keys, params, ga, populations, 0))
    seconds = time.perf_counter() - start
    individuals = len(points) * len(seeds) * config.population_size
    single = [r for s in check.results["steps"] if s["step"] == "generation" and s["status"] == "ok" for r in s["rows"]
              if r.get("status") == "ok" and r["kernel"] == kernel and r["seeds"] == len(seeds)]
    ratio = seconds / (len(points) * single[0]["seconds"]) if single else None
    check.say(f"  sweep ({kernel}) {len(points)} points x {len(seeds)} seeds: {seconds:.2f} s a generation "
              f"(compile {compile_s:.1f} s)"
              + (f"; over {len(points)} single generations: {ratio:.2f}" if ratio else ""))
    return {"kernel": kernel, "points": len(points), "seeds": len(seeds), "individuals": individuals,
            "compile_s": compile_s, "seconds": seconds, "over_single_generations": ratio,
            "lane_steps_per_s": individuals * config.lifetime_steps / seconds,
            "best_fitness": np.asarray(stats.fitness).max(-1).reshape(len(points), len(seeds)).tolist()}


#: The kernels the ``phases`` step times: (step kernel, how the kernel observes; None: the XLA step).
PHASE_KERNELS = (("xla", None), ("pallas", "entries"), ("pallas", "points"))


def phases(check: Check) -> dict:
    """Every phase of the benchmark, the XLA step and the kernel at every lane count, and the kernel observing by
    points (``kernel_retina``) at the most lanes."""
    from imrl_jax.commands import bench
    from imrl_jax import conditions
    from imrl_jax.agent import kernel_work

    rows, counted = [], {}
    for name, condition, phase, _ in bench.PHASES:
        if check.sizes.conditions and condition not in check.sizes.conditions:
            continue
        for kernel, retina in PHASE_KERNELS:
            fields = () if retina is None else (("kernel_retina", retina),)
            # The kernel observing by points at the most lanes only, where its choice is judged (PERFORMANCE.md).
            for lanes in check.sizes.lanes if retina != "points" else check.sizes.lanes[-1:]:
                row = {"phase": name, "kernel": kernel, "lanes": lanes, **({"retina": retina} if retina else {})}
                if not check.fits(10 + lanes / 30_000):
                    rows.append({**row, "status": "skipped (budget)"})
                    continue
                with check.piece(row, rows):
                    check.stage = "api"
                    program = bench.phase_program(condition, phase, lanes, check.sizes.phase_steps,
                                                  step_kernel=kernel, fields=fields)
                    key = ("phase", condition, phase, lanes, check.sizes.phase_steps, kernel, retina)
                    executable, compile_s = compile_once(check, key, program.fn, *program.args)
                    seconds, shortest = timed(executable, program.args, check.sizes.repeats)
                    row.update(steps=check.sizes.phase_steps, compile_s=compile_s,
                               lane_steps_per_s=program.lane_steps / seconds,
                               best_lane_steps_per_s=program.lane_steps / shortest,
                               program_bytes=program_bytes(executable), status="ok")
                    if kernel == "pallas":  # the issue rate it reaches (PERFORMANCE.md "How far from the hardware")
                        if (condition, phase, retina) not in counted:
                            counted[condition, phase, retina] = kernel_work.loop_work(
                                program.config, getattr(conditions, phase))["warp_instructions"]
                        count = counted[condition, phase, retina]
                        row.update(warp_instructions=count, warp_instructions_per_s=row["lane_steps_per_s"] * count)
                    label = kernel if retina in (None, "entries") else f"{kernel}/{retina}"
                    check.say(f"  {name:22s} {label:13s} {lanes:8,d} lanes: {row['lane_steps_per_s']:14,.0f} "
                              f"lane-steps/s, compile {compile_s:5.1f} s")
    return {"rows": rows}


def models(check: Check) -> dict:
    """Whole lives of every model on the kernel at one lane count: each row of the condition table, then the first
    condition's selector on its own time-scale (``Sizes.selector_options``); each one's speed beside LE-LS's."""
    from imrl_jax import conditions
    from imrl_jax.commands import bench

    names = check.sizes.conditions or conditions.NAMES
    cases = [(name, "", ()) for name in names] + [(names[0] if check.sizes.conditions else "LE-LS", option, fields)
                                                  for option, fields in check.sizes.selector_options]
    rows = []
    for name, option, fields in cases:
        row = {"condition": name, "options": option, "kernel": "pallas", "lanes": check.sizes.model_lanes}
        if not check.fits(10):
            rows.append({**row, "status": "skipped (budget)"})
            continue
        with check.piece(row, rows):
            check.stage = "api"
            program = bench.lifetime_program(check.sizes.model_lanes, check.sizes.life_task_steps,
                                             step_kernel="pallas", condition=name, fields=fields)
            executable, compile_s = compile_program(check, program.fn, *program.args)
            seconds, shortest = timed(executable, program.args, check.sizes.repeats)
            row.update(individuals=program.args[2].shape[0], compile_s=compile_s, seconds=seconds,
                       lane_steps_per_s=program.lane_steps / seconds,
                       best_lane_steps_per_s=program.lane_steps / shortest, status="ok")
            check.say(f"  {name + (' +' + option if option else ''):18s} pallas {check.sizes.model_lanes:8,d} lanes: "
                      f"{row['lane_steps_per_s']:14,.0f} lane-steps/s, compile {compile_s:5.1f} s")
    base = next((r for r in rows if r.get("status") == "ok" and r["condition"] == "LE-LS" and not r["options"]),
                next((r for r in rows if r.get("status") == "ok"), None))
    for row in rows:
        if base is not None and row.get("status") == "ok":
            row["over_le_ls" if base["condition"] == "LE-LS" else "over_first"] = (
                row["lane_steps_per_s"] / base["lane_steps_per_s"])
    return {"rows": rows}
