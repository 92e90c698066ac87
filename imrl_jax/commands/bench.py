"""Benchmarks of the lifetime kernel (section 2's lives) against the NumPy reference.

    python -m imrl_jax.bench [--lanes 1,50,300,3000] [--steps 1000] [--repeats 5] [--json PATH]
                             [--kernel xla,pallas] [--world NAME [--world-set FIELD=VALUE] [--only-world]]

One lane is one individual on one task (in childhood, one individual). For every phase
(LE-LS childhood; the adult phases of LE-LS/EE-LS, EE-ES and SLE) and lane count, it
reports lane-steps per second (median of ``repeats`` timed runs after compilation), the
compile time and the compiled program's memory; then the NumPy reference on the same
phase, and the speed-up measured in the same run. Last, the headline: whole LE-LS lives of
``lanes / 6`` individuals (childhood 1.5 x task steps, six tasks) for each of
``--lifetime-lanes`` (300 and 3,000 by default), against the reference's life.
On CPU the lanes are split over one XLA device per core (``--cpu-devices``).
``--kernel`` names the step kernels to measure (``Config.step_kernel``; default xla): on a
GPU, ``--kernel xla,pallas`` measures both in one run. Off a GPU the Pallas kernel is
interpreted, which measures nothing useful. ``--world NAME`` adds another world's section
(:mod:`imrl_jax.commands.bench_worlds`: the agent's childhood and adulthood there against the world stepped alone
with random actions, at ``--lanes`` and ``--steps``); ``--only-world`` measures that section alone.
"""

from __future__ import annotations

import importlib
import json
import os
import platform
import resource
import statistics
import sys
import time
import jax
import numpy as np

from imrl_jax.commands.bench_lanes import Program, alternate, lane_inputs
from imrl_jax.config import make_config
from imrl_jax.evolution.devices import use_host_cores

#: (name, condition, phase attribute of imrl_jax.agent.lifetime, reference phase name)
PHASES = (
    ("LE-LS childhood", "LE-LS", "CHILDHOOD", "childhood"),
    ("LE-LS/EE-LS adulthood", "EE-LS", "ADULT_LEARNING_SELECTOR", "adult-ls"),
    ("EE-ES adulthood", "EE-ES", "ADULT_EVOLVED_SELECTOR", "adult-es"),
    ("SLE adulthood", "SLE", "ADULT_SINGLE_EXPERT", "sle"),
)


def _time(fn, *args, repeats: int, once_over: float | None = None) -> tuple[float, float]:
    """Median and shortest wall time of ``repeats`` calls (after one untimed call; or that call's time alone when
    it took over ``once_over`` seconds, for a compiled program too long to run again).

    The shortest is what the machine can do when nothing else runs on it; on a shared
    machine the median can be far slower.
    """
    start = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - start
    if once_over is not None and first > once_over:
        return first, first
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def _module(package: str, name: str):
    """A package's module by its name, where the revision keeps it: ``agent/lifetime.py`` (or ``world/env.py``), or
    (revisions before the sub-packages) ``lifetime.py``."""
    for path in (f"{package}.{name}", f"{package}.agent.{name}", f"{package}.world.{name}"):
        try:
            return importlib.import_module(path)
        except ModuleNotFoundError as missing:
            if missing.name not in (path, path.rsplit(".", 1)[0]):
                raise  # a module that exists, failing to import another
    raise ModuleNotFoundError(f"{package} has no module {name}", name=f"{package}.{name}")


def _modules(package: str):
    return tuple(_module(package, name) for name in ("config", "lifetime", "networks"))


def _phase(package: str, name: str):
    """The phase ``name`` (e.g. ``CHILDHOOD``) of a package: in its condition table, or (revisions before the
    table) in its lifetime module."""
    try:
        return getattr(_module(package, "conditions"), name)
    except ModuleNotFoundError:
        return getattr(_module(package, "lifetime"), name)


def _kernel_field(step_kernel: str, config_module) -> dict:
    # Only where the revision has the field (revisions from before it are the XLA step); always there, as its
    # default "auto" would be the kernel on a GPU.
    return {"step_kernel": step_kernel} if hasattr(config_module.Config, "step_kernel") else {}


def phase_program(condition: str, phase_name: str, lanes: int, steps: int, package: str = "imrl_jax",
                  step_kernel: str = "xla", fields: tuple = ()) -> Program:
    """One phase (a name of the condition table, e.g. ``CHILDHOOD``) run for ``steps`` steps on ``lanes`` lanes, with
    the Config ``fields`` (name, value) pairs (none).

    ``package`` names the imrl_jax whose modules build it (``python -m imrl_jax.compare``
    passes an earlier revision's, imported under another name).
    """
    config_module, L, networks = _modules(package)
    env = _module(package, "env")
    # A phase starts in the world's state (the arena's at a pose), or (revisions before worlds) at the pose.
    start = env.at if hasattr(env, "at") else (lambda pose: pose)
    config = config_module.make_config("paper", condition=condition, childhood_steps=steps, task_steps=steps,
                                       num_bins=1, **_kernel_field(step_kernel, config_module), **dict(fields))
    phase = _phase(package, phase_name)
    params = config.learning_params()

    def lane(key, genome):
        agent = networks.decode(config, genome)
        if phase.intrinsic:
            task = L.childhood_task(config)
            pose = L.random_pose(key, config)
        else:
            agent = L.adult_agent(config, agent)
            task = L.task_spec(config, 0)
            pose = task.start
        state, curves = L.run_phase(key, config, phase, params, task, L.init_state(config, agent, start(pose)), steps)
        return curves.reaches, curves.selections

    return Program(jax.jit(jax.vmap(lane)), lane_inputs(config, lanes), lanes * steps, config)


def lifetime_program(lanes: int, task_steps: int, package: str = "imrl_jax", step_kernel: str = "xla",
                     condition: str = "LE-LS", fields: tuple = ()) -> Program:
    """Whole lives of ``condition`` (LE-LS) of ``lanes / 6`` individuals (childhood 1.5 x task steps), with the Config
    ``fields`` (name, value) pairs (none); ``package`` as above."""
    config_module, L, _ = _modules(package)
    config = config_module.make_config("paper", condition=condition, task_steps=task_steps,
                                       childhood_steps=task_steps * 3 // 2, num_bins=10,
                                       **_kernel_field(step_kernel, config_module), **dict(fields))
    individuals = max(1, lanes // config.num_tasks)
    _, genomes = lane_inputs(config, individuals)
    return Program(L.make_evaluate(config), (jax.random.key(0), config.learning_params(), genomes),
                   individuals * config.lifetime_steps, config)


def bench_phase(condition: str, phase_name: str, lanes: int, steps: int, repeats: int,
                step_kernel: str = "xla") -> dict:
    """Lane-steps per second of one phase run for ``steps`` steps on ``lanes`` lanes."""
    program = phase_program(condition, phase_name, lanes, steps, step_kernel=step_kernel)
    start = time.perf_counter()
    compiled = program.fn.lower(*program.args).compile()
    compile_s = time.perf_counter() - start
    memory = compiled.memory_analysis()
    seconds, shortest = _time(compiled, *program.args, repeats=repeats)
    return {"lanes": lanes, "steps": steps, "seconds": seconds, "lane_steps_per_s": program.lane_steps / seconds,
            "best_lane_steps_per_s": program.lane_steps / shortest,
            "compile_s": compile_s,
            "program_bytes": int(memory.temp_size_in_bytes + memory.argument_size_in_bytes
                                 + memory.output_size_in_bytes)}


def bench_reference_phase(condition: str, reference_phase: str, steps: int) -> dict:
    """Steps per second of the NumPy reference on one lane of the same phase."""
    from imrl_jax.agent import reference
    from imrl_jax.agent.state import draw_many

    config = make_config("paper", condition=condition, childhood_steps=steps, task_steps=steps, num_bins=1)
    rng = np.random.default_rng(0)
    weights = reference.decode(config, rng.uniform(-1, 1, config.num_genes))
    draws = draw_many(jax.random.key(0), steps, config.draw_block)
    task = None if reference_phase == "childhood" else 0
    start_pose = (200.0, 200.0, 0.3) if task is None else (*config.tasks[0].start, np.radians(config.tasks[0].heading_deg))
    start = time.perf_counter()
    reference.run_phase(config, reference_phase, weights, start_pose, np.asarray(draws.u, np.float64),
                        np.asarray(draws.z, np.float64), task=task)
    seconds = time.perf_counter() - start
    return {"steps": steps, "seconds": seconds, "lane_steps_per_s": steps / seconds}


def bench_lifetime(lanes: int, task_steps: int, repeats: int, step_kernel: str = "xla") -> dict:
    """The headline: whole LE-LS lives of ``lanes / 6`` individuals (lane-steps per second)."""
    program = lifetime_program(lanes, task_steps, step_kernel=step_kernel)
    config, genomes = program.config, program.args[2]
    individuals = genomes.shape[0]
    start = time.perf_counter()
    jax.block_until_ready(program.fn(*program.args))
    compile_s = time.perf_counter() - start
    seconds, shortest = _time(program.fn, *program.args, repeats=repeats)
    return {"kernel": step_kernel, "individuals": individuals, "lanes": individuals * config.num_tasks,
            "childhood_steps": config.childhood_steps, "task_steps": config.task_steps,
            "seconds": seconds, "compile_and_first_run_s": compile_s,
            "lane_steps_per_s": program.lane_steps / seconds, "best_lane_steps_per_s": program.lane_steps / shortest}


def bench_reference_life(task_steps: int) -> float:
    """Lane-steps per second of the NumPy reference living one life of the whole-life benchmark."""
    from imrl_jax.agent import reference
    from imrl_jax.agent.lifetime import lifetime_keys, random_pose
    from imrl_jax.agent.state import draw_many

    program = lifetime_program(1, task_steps)
    config, (key, _, genomes) = program.config, program.args
    keys = lifetime_keys(key, config.num_tasks)
    genome = np.asarray(genomes[0], np.float64)
    pose = random_pose(keys.pose, config)
    child = draw_many(keys.childhood, config.childhood_steps, config.draw_block)
    tasks = jax.vmap(draw_many, (0, None, None))(keys.tasks, config.task_steps, config.draw_block)
    start = time.perf_counter()
    reference.live(config, genome, (*np.asarray(pose.pos, np.float64), float(pose.heading)),
                   np.asarray(child.u, np.float64), np.asarray(child.z, np.float64),
                   np.asarray(tasks.u, np.float64), np.asarray(tasks.z, np.float64))
    return config.lifetime_steps / (time.perf_counter() - start)


def machine() -> dict:
    device = jax.devices()[0]
    return {"backend": jax.default_backend(), "device": getattr(device, "device_kind", str(device)),
            "num_devices": len(jax.devices()), "cpu_count": os.cpu_count(), "machine": platform.machine(),
            "jax_version": jax.__version__}


def run(lane_counts, steps: int, repeats: int, reference_steps: int, lifetime_lanes,
        lifetime_task_steps: int, log=print, kernels=("xla",)) -> dict:
    """Every measurement, as a JSON-friendly dict (also printed as a table through ``log``)."""
    result = {**machine(), "phases": [], "repeats": repeats, "kernels": list(kernels)}
    log(f"backend {result['backend']} ({result['device']} x {result['num_devices']}, {result['cpu_count']} cpus), "
        f"jax {result['jax_version']}; medians of {repeats} runs")
    if "pallas" in kernels and result["backend"] != "gpu":
        log("note: off a GPU the pallas kernel runs in Pallas's interpreter; its rows are not its speed")
    log(f"{'phase':24s} {'kernel':>6s} {'lanes':>6s} {'lane-steps/s':>14s} {'best run':>12s} {'vs reference':>12s} "
        f"{'compile s':>9s} {'program MB':>10s}")
    for name, condition, phase, reference_phase in PHASES:
        ref = bench_reference_phase(condition, reference_phase, reference_steps)
        for kernel in kernels:
            for lanes in lane_counts:
                row = bench_phase(condition, phase, lanes, steps, repeats, kernel)
                row.update(phase=name, kernel=kernel, reference_lane_steps_per_s=ref["lane_steps_per_s"],
                           speedup=row["lane_steps_per_s"] / ref["lane_steps_per_s"])
                result["phases"].append(row)
                log(f"{name:24s} {kernel:>6s} {lanes:6d} {row['lane_steps_per_s']:14,.0f} "
                    f"{row['best_lane_steps_per_s']:12,.0f} {row['speedup']:11,.0f}x "
                    f"{row['compile_s']:9.1f} {row['program_bytes'] / 2**20:10.1f}")
        log(f"{name + ' (reference)':24s} {'':6s} {1:6d} {ref['lane_steps_per_s']:14,.0f}")
    result["lifetimes"] = []
    reference_rate = bench_reference_life(lifetime_task_steps)
    for kernel in kernels:
        for lanes in lifetime_lanes:
            life = bench_lifetime(lanes, lifetime_task_steps, repeats, kernel)
            life.update(reference_lane_steps_per_s=reference_rate, speedup=life["lane_steps_per_s"] / reference_rate)
            result["lifetimes"].append(life)
            log(f"LE-LS whole life ({kernel}): {life['individuals']} individuals ({life['lanes']} adult lanes), "
                f"childhood {life['childhood_steps']:,} + 6 x {life['task_steps']:,} steps: "
                f"{life['lane_steps_per_s']:,.0f} lane-steps/s (best run {life['best_lane_steps_per_s']:,.0f}); "
                f"reference {life['reference_lane_steps_per_s']:,.0f}; speed-up {life['speedup']:,.0f}x")
    result["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    log(f"peak resident memory of this process: {result['peak_rss_mb']:.0f} MB")
    return result


def sweep_benchmark(num_points: int, num_seeds: int = 2, task_steps: int = 500, pairs: int = 5, log=print) -> dict:
    """A generation of a k-point sweep (``evolve --sweep``, one program) against k generations of a single run.

    LE-LS under the paper's preset at ``task_steps`` per task (childhood 1.5 x), ``num_seeds`` seeds of 50; the two
    programs' timed generations alternate (``pairs`` of each, after compilation), so both see the same machine.
    Returns the medians and ``ratio``: the sweep's generation over k single ones (at most 1: the sweep costs no more).
    """
    from imrl_jax.commands import evolve, evolve_sweep
    from imrl_jax.evolution.ga import GA
    from imrl_jax.evolution.devices import make_mesh, population_sharding, replicated, to_global

    config = make_config("paper", condition="LE-LS", task_steps=task_steps, childhood_steps=task_steps * 3 // 2,
                         num_bins=1)
    seeds = list(range(num_seeds))
    mesh = make_mesh()
    single_sharding = population_sharding(mesh, num_seeds, config.population_size)
    single = evolve.make_step(config, GA(config), single_sharding)
    state = evolve.initial_state(config, seeds, single_sharding)
    keys = to_global(evolve.evolution_keys(state.key_data), replicated(mesh))
    single_args = (keys, config.learning_params(), state.populations, (), 0)
    settings = [dict(trace_lambda=v) for v in np.linspace(0.0, 0.98, num_points)]
    points = evolve_sweep.make_points(config, seeds, settings)
    sweep_sharding = population_sharding(mesh, num_points * num_seeds, config.population_size)
    sweep = evolve_sweep.make_sweep_step(config, sweep_sharding)
    params, ga = evolve_sweep.batched_values(points, num_seeds)
    sweep_args = (to_global(evolve.evolution_keys(np.tile(state.key_data, (num_points, 1))), replicated(mesh)),
                  params, ga, to_global(np.tile(np.asarray(state.populations), (num_points, 1, 1)), sweep_sharding), 0)
    timed = {}
    for name, fn, args in (("single", single, single_args), ("sweep", sweep, sweep_args)):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        timed[f"{name}_compile_s"] = time.perf_counter() - start
    timed.update(alternate({"single": (single, single_args), "sweep": (sweep, sweep_args)}, pairs))
    single_s, sweep_s = statistics.median(timed["single"]), statistics.median(timed["sweep"])
    result = dict(points=num_points, seeds=num_seeds, population=config.population_size, task_steps=task_steps,
                  single_generation_s=single_s, sweep_generation_s=sweep_s, ratio=sweep_s / (num_points * single_s),
                  single_compile_s=timed["single_compile_s"], sweep_compile_s=timed["sweep_compile_s"],
                  devices=len(jax.devices()), platform=jax.default_backend())
    log(f"LE-LS generation of {num_seeds} seed(s) x {config.population_size}, {task_steps} steps per task: single run "
        f"{single_s:.2f} s (median of {pairs}); sweep of {num_points} points {sweep_s:.2f} s; the sweep over "
        f"{num_points} single generations: {result['ratio']:.2f} (compile {timed['single_compile_s']:.1f} s and "
        f"{timed['sweep_compile_s']:.1f} s)")
    return result


def main(argv=None) -> int:
    from imrl_jax.runs import cli

    return cli.exit_codes(_main)(argv)


def parser():
    """The bench command line's parser."""
    from imrl_jax.runs import cli

    p = cli.Parser(prog="python -m imrl_jax.bench", description=__doc__.split("\n")[0],
                   formatter_class=cli.HelpFormatter)
    p.add_argument("--lanes", default="1,50,300,3000", help="comma-separated lane counts")
    p.add_argument("--steps", type=int, default=1000, help="steps per timed phase run")
    p.add_argument("--repeats", type=int, default=5, help="timed runs after compilation (median)")
    p.add_argument("--reference-steps", type=int, default=500, help="steps of the reference per phase")
    p.add_argument("--lifetime-lanes", default="300,3000",
                   help="comma-separated adult lane counts of the whole-life benchmark (6 per individual)")
    p.add_argument("--lifetime-task-steps", type=int, default=2000, help="steps per task of the whole life")
    p.add_argument("--cpu-devices", type=int, default=0, help="CPU devices (0: one per core)")
    p.add_argument("--kernel", default="xla", help="comma-separated step kernels: xla, pallas (GPU)")
    p.add_argument("--sweep-points", type=int, default=0,
                   help="instead: a generation of a sweep of this many points (evolve --sweep) against as many "
                        "generations of a single run, alternating (--repeats pairs, --lifetime-task-steps)")
    cli.add_world(p, "also measure the agent in this world against the world stepped alone with random actions")
    p.add_argument("--only-world", action="store_true", help="measure only the --world section")
    p.add_argument("--json", help="also write the results to this JSON file")
    return p


def _main(argv=None) -> int:
    """The command: parse, check every option (nothing written), then measure through ``cli.execute``."""
    from imrl_jax.runs import cli
    from imrl_jax.runs.cli import UsageError
    from imrl_jax.config import STEP_KERNELS
    from imrl_jax.runs.rundir import check_writable

    args = parser().parse_args(argv)
    if args.sweep_points < 0 or args.sweep_points > 1000:
        raise UsageError("--sweep-points: must be in 0..1000")
    kernels = args.kernel.split(",")
    if not all(k in STEP_KERNELS for k in kernels):
        raise UsageError(f"--kernel: expected {' or '.join(STEP_KERNELS)}, separated by commas, got {args.kernel!r}")
    counts = {}
    for name in ("lanes", "lifetime_lanes"):
        text = getattr(args, name)
        try:
            counts[name] = [int(n) for n in text.split(",")]
        except ValueError:
            counts[name] = []
        if not counts[name] or min(counts[name]) < 1:
            raise UsageError(f"--{name.replace('_', '-')}: expected positive integers separated by commas, "
                             f"got {text!r}")
        cli.check_at_most(f"--{name.replace('_', '-')}", max(counts[name]), cli.MAX_LANES)
    for name in ("steps", "repeats", "reference_steps", "lifetime_task_steps"):
        cli.check_at_least(f"--{name.replace('_', '-')}", getattr(args, name))
        cli.check_at_most(f"--{name.replace('_', '-')}", getattr(args, name), cli.MAX_STEPS)
    if args.lifetime_task_steps % 10:
        raise UsageError("--lifetime-task-steps: must be a multiple of 10")
    if args.json is not None:  # checked before the measurements, which take minutes
        cli.check_out(args.json, "--json")
        if os.path.isdir(args.json):
            raise UsageError(f"--json: {args.json} is a directory")
        check_writable(os.path.dirname(os.path.abspath(args.json)), "--json")
    cli.check_cpu_devices(args.cpu_devices)  # at most 4 per core: each device holds its own runtime
    world, world_given = None, args.world is not None or bool(args.world_set)
    if world_given and args.sweep_points:
        raise UsageError("--world: a world's section is not measured with --sweep-points")
    if args.only_world and not world_given:
        raise UsageError("--only-world: give the world (--world NAME)")
    if world_given:
        from imrl_jax.commands import bench_worlds

        use_host_cores(args.cpu_devices or None)  # now: importing the world's library starts the backend
        world = cli.apply_world(bench_worlds.base_config(args.steps), args)
    return cli.execute(cli.Call(lambda: measure(args, counts, kernels, world), counts=counts, kernels=kernels,
                                world=world))


def measure(args, counts: dict, kernels: list[str], world=None) -> int:
    """The benchmark the command line checked (``world``: the config of the ``--world`` section); its results written
    to ``--json`` if given."""
    use_host_cores(args.cpu_devices or None)
    if args.sweep_points:
        result = sweep_benchmark(args.sweep_points, task_steps=args.lifetime_task_steps, pairs=args.repeats)
    elif args.only_world:
        result = {**machine(), "repeats": args.repeats}
    else:
        result = run(counts["lanes"], args.steps, args.repeats, args.reference_steps, counts["lifetime_lanes"],
                     args.lifetime_task_steps, kernels=kernels)
    if world is not None:
        from imrl_jax.commands import bench_worlds

        result["world"] = bench_worlds.run(world, counts["lanes"], args.repeats)
    if args.json:
        from imrl_jax.runs.rundir import write_atomic

        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        write_atomic(args.json, json.dumps(result, indent=2).encode())
    return 0


if __name__ == "__main__":
    sys.exit(main())
