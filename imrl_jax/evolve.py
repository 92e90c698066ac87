"""``python -m imrl_jax.evolve``: the paper's evolutions (section 2; Fig. 3a) as one program.

    python -m imrl_jax.evolve --cond EE-LS --seeds 10 [--preset paper] [--out runs/EE-LS]

Seeds are a batch axis: ``--seeds 10`` runs ten independent evolutions (seed 0..9, or
``--first-seed``) in one jitted generation step, each reproducible from its own seed.
The seeds x population axis is sharded over all devices (and, under ``jax.distributed``,
over all processes). Every ``--checkpoint-every`` generations the run is checkpointed
with orbax; ``--resume`` continues from the latest good checkpoint and ends bitwise
where an uninterrupted run would. The run directory holds ``config.json``,
``history.csv`` (best, mean, std and the best individual's task performances per seed
per generation), ``fitness.png`` (best fitness, mean and std over seeds, as Fig. 3a),
``final_population.npz`` and ``checkpoints/``; all are rewritten as the run goes.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import sys
import time
from typing import Sequence

import jax
import numpy as np

import imrl_jax
from imrl_jax.checkpoint import Checkpointer, History, RunState, empty_history, git_commit
from imrl_jax.cli import HelpFormatter, UsageError, parse_sets, user_errors
from imrl_jax.devices import (make_mesh, population_sharding, replicated, sharded_axis, to_global, to_host,
                              use_host_cores)
from imrl_jax.config import CONDITIONS, EVOLVED_CONDITIONS, PRESETS, Config, ConfigError, make_config
from imrl_jax.ga import init_population, make_generation
from imrl_jax.progress import Progress
from imrl_jax.rundir import check_writable, read_config, write_atomic

__all__ = ["UsageError", "parse_sets", "write_atomic", "run", "main"]  # the first three re-exported

# ----------------------------------------------------------------------------- state


def seed_keys(seeds: Sequence[int]) -> jax.Array:
    """One typed key per seed."""
    return jax.vmap(jax.random.key)(np.asarray(seeds, np.uint32))


def initial_state(config: Config, seeds: Sequence[int], sharding) -> RunState:
    """Generation 0 of every seed (drawn from the seed's own key)."""
    keys = seed_keys(seeds)
    init_keys = jax.vmap(lambda k: jax.random.fold_in(k, 0))(keys)
    populations = np.asarray(jax.vmap(lambda k: init_population(k, config))(init_keys))
    shape = populations.shape
    history = empty_history(config.num_generations, len(seeds), config.num_tasks)
    return RunState(
        generation=np.asarray(0, np.int32),
        populations=to_global(populations, sharding),
        evaluated=to_global(np.zeros(shape, np.float32), sharding),
        fitness=to_global(np.zeros(shape[:2], np.float32), sharding),
        key_data=np.asarray(jax.random.key_data(keys)),
        history=history,
    )


def evolution_keys(key_data: np.ndarray) -> jax.Array:
    """The keys the generations of each seed draw from (distinct from the initial population's)."""
    keys = jax.random.wrap_key_data(np.asarray(key_data))
    return jax.vmap(lambda k: jax.random.fold_in(k, 1))(keys)


def record(history: History, generation: int, fitness: np.ndarray, performance: np.ndarray) -> History:
    """History with the statistics of one generation written in."""
    best_index = np.argmax(fitness, axis=1)
    seeds = np.arange(fitness.shape[0])
    best, mean, std, best_perf = (np.array(h) for h in history)
    best[generation] = fitness.max(1)
    mean[generation] = fitness.mean(1)
    std[generation] = fitness.std(1)
    best_perf[generation] = performance[seeds, best_index]
    return History(best, mean, std, best_perf)


# ----------------------------------------------------------------------------- outputs


def history_csv(history: History, generations: int, seeds: Sequence[int]) -> str:
    """The history of the finished generations as CSV text."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    num_tasks = history.best_performance.shape[-1]
    writer.writerow(["generation", "seed", "best", "mean", "std"] + [f"best_task{i + 1}" for i in range(num_tasks)])
    for g in range(generations):
        for s, seed in enumerate(seeds):
            writer.writerow([g, seed] + [f"{float(history.best[g, s]):.6f}", f"{float(history.mean[g, s]):.6f}",
                                         f"{float(history.std[g, s]):.6f}"]
                            + [f"{float(p):.6f}" for p in history.best_performance[g, s]])
    return out.getvalue()


def write_outputs(out_dir: str, config: Config, seeds: Sequence[int], state: RunState) -> None:
    """Rewrite history.csv, fitness.png and final_population.npz from a state."""
    from imrl_jax.plotting import plot_fitness, save

    done = int(state.generation)
    write_atomic(os.path.join(out_dir, "history.csv"), history_csv(state.history, done, seeds).encode())
    buffer = io.BytesIO()
    np.savez(buffer, seeds=np.asarray(seeds), generation=done, evaluated=to_host(state.evaluated),
             fitness=to_host(state.fitness), next_population=to_host(state.populations))
    write_atomic(os.path.join(out_dir, "final_population.npz"), buffer.getvalue())
    if done:
        scale = "" if _is_paper_scale(config) else ", reduced scale"
        save(plot_fitness({config.condition: state.history.best[:done].T},
                          title=f"{config.condition}: best fitness per generation, mean and std over "
                                f"{len(seeds)} seed(s){scale}", ylabel="best fitness of the population"),
             os.path.join(out_dir, "fitness.png"))


def _is_paper_scale(config: Config) -> bool:
    paper = make_config("paper", condition=config.condition)
    return all(getattr(config, f) == getattr(paper, f) for f in
               ("childhood_steps", "task_steps", "population_size", "num_generations", "num_parents"))


# ----------------------------------------------------------------------------- run


def check_run_dir(out_dir: str, config: Config, seeds: Sequence[int], resume: bool) -> None:
    """Refuse to overwrite another run; on resume refuse a changed config. Raises UsageError."""
    config_path = os.path.join(out_dir, "config.json")
    exists = os.path.exists(config_path)
    if exists and not resume:
        raise UsageError(f"{out_dir} already holds a run (config.json); pass --resume to continue it "
                         f"or choose another --out")
    if resume and not exists:
        raise UsageError(f"--resume: {out_dir} holds no run to resume (no config.json)")
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise UsageError(f"--out: {out_dir} is not a directory")
    if exists:
        saved_config, saved_seeds = read_config(out_dir)
        if saved_seeds != list(seeds):
            raise UsageError(f"--resume: seeds {list(seeds)} differ from the run's {saved_seeds}")
        differing = [name for name in saved_config.model_differences(config)
                     if not (name == "num_generations" and config.num_generations > saved_config.num_generations)]
        if differing:  # a run may be extended: its generations go on from the last one done
            changes = "; ".join(f"{name} is {getattr(config, name)!r} but the run used {getattr(saved_config, name)!r}"
                                + (" (a resumed run may only grow it)" if name == "num_generations" else "")
                                for name in differing)
            raise UsageError(f"--resume: the config differs from the run's in {out_dir}: {changes}")


def extend_config_json(out_dir: str, config: Config) -> None:
    """Record a grown ``num_generations`` in the run's config.json (with when it grew from what)."""
    path = os.path.join(out_dir, "config.json")
    with open(path) as f:
        info = json.load(f)
    old = int(info["config"]["num_generations"])
    if old == config.num_generations:
        return
    info["config"]["num_generations"] = config.num_generations
    info.setdefault("extended", []).append(dict(num_generations=[old, config.num_generations],
                                                 at=time.strftime("%Y-%m-%dT%H:%M:%S%z"), git_commit=git_commit()))
    write_atomic(path, json.dumps(info, indent=2).encode())


def run(config: Config, out_dir: str, seeds: Sequence[int] = (0,), *, resume: bool = False,
        checkpoint_every: int = 1, keep: int = 3, quiet: bool = False) -> RunState:
    """Evolve ``config.condition`` for every seed into ``out_dir``; return the final state."""
    if not config.spec.evolved:
        raise UsageError(f"--cond: {config.condition} is not evolved (it learns each task from scratch); "
                         f"test it with: python -m imrl_jax.learning_test --cond {config.condition} --out DIR")
    seeds = [int(s) for s in seeds]
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise UsageError("--seeds: need at least one seed, all distinct and non-negative")
    if checkpoint_every < 1:
        raise UsageError("--checkpoint-every: must be at least 1")
    if keep < 1:
        raise UsageError("--keep: must be at least 1 (a run keeps its latest checkpoint to resume from)")
    check_writable(out_dir)
    check_run_dir(out_dir, config, seeds, resume)
    if jax.process_count() > 1:  # every process checks before the leader writes
        from jax.experimental import multihost_utils

        multihost_utils.sync_global_devices("imrl_jax.evolve: run directory checked")
    leader = jax.process_index() == 0

    mesh = make_mesh()
    sharding = population_sharding(mesh, len(seeds), config.population_size)
    state = initial_state(config, seeds, sharding)
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as error:
        raise UsageError(f"--out: cannot create {out_dir} ({error.strerror or error})") from None
    checkpointer = Checkpointer(os.path.join(out_dir, "checkpoints"), keep=keep)
    try:
        return _evolve(config, out_dir, seeds, state, sharding, mesh, checkpointer, resume=resume,
                       checkpoint_every=checkpoint_every, quiet=quiet or not leader, leader=leader)
    finally:
        checkpointer.close()


def _evolve(config: Config, out_dir: str, seeds: list[int], state: RunState, sharding, mesh,
            checkpointer: Checkpointer, *, resume: bool, checkpoint_every: int, quiet: bool, leader: bool) -> RunState:
    """The generations of :func:`run` after its checks (resuming from the latest good checkpoint)."""
    progress = Progress(config.num_generations, quiet=quiet, first_index=0)
    meta = {"config": config.to_dict(), "seeds": seeds}
    if resume:
        restored = checkpointer.restore_latest(state, warn=progress.message)
        if restored is None:
            if checkpointer.steps():
                raise UsageError(f"--resume: no readable checkpoint in {checkpointer.directory}")
            progress.message(f"no checkpoint in {checkpointer.directory} yet: starting from generation 0")
        else:
            state, saved_meta = restored
            if not np.array_equal(state.key_data, np.asarray(jax.random.key_data(seed_keys(seeds)))):
                raise UsageError("--resume: the checkpoint's keys do not match the seeds")
            if int(state.generation) > config.num_generations:  # only if config.json was edited by hand
                raise UsageError(f"--resume: config field num_generations is {config.num_generations} but "
                                 f"{int(state.generation)} generations are done")
            if leader:
                extend_config_json(out_dir, config)
            progress = Progress(config.num_generations, done=int(state.generation), quiet=quiet, first_index=0,
                                elapsed=float(saved_meta.get("elapsed_seconds", 0.0)))
            progress.message(f"resuming {out_dir} after generation {int(state.generation) - 1} "
                             f"({int(state.generation)} of {config.num_generations} done; checkpoint of commit "
                             f"{saved_meta.get('git_commit', 'unknown')[:12]})")
    elif leader:
        info = {**meta, "version": imrl_jax.__version__, "git_commit": git_commit(),
                "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "devices": len(jax.devices()),
                "processes": jax.process_count(), "sharded_axis": sharded_axis(sharding)}
        write_atomic(os.path.join(out_dir, "config.json"), json.dumps(info, indent=2).encode())

    generation = make_generation(config, sharding)
    keys = to_global(evolution_keys(state.key_data), replicated(mesh))
    params = config.learning_params()
    lane_steps = len(seeds) * config.population_size * config.lives_per_fitness * config.lifetime_steps
    first = int(state.generation)
    for g in range(first, config.num_generations):
        start = time.perf_counter()
        evaluated = state.populations
        populations, stats = generation(keys, params, evaluated, g)
        fitness, performance = to_host(stats.fitness), to_host(stats.performance)
        seconds = time.perf_counter() - start
        state = RunState(np.asarray(g + 1, np.int32), populations, evaluated, stats.fitness, state.key_data,
                         record(state.history, g, fitness, performance))
        best = fitness.max(1)
        progress.update(g + 1, float(best.max()), float(fitness.mean()), lane_steps / seconds,
                        scores=f"best fitness: max over seeds {best.max():.4f}, mean over seeds {best.mean():.4f}")
        if (g + 1) % checkpoint_every == 0 or g + 1 == config.num_generations:
            # every process: orbax saves collectively
            checkpointer.save(state, {**meta, "elapsed_seconds": round(progress.elapsed(), 3)})
            _write_outputs_from_leader(out_dir, config, seeds, state, leader)
    if first == config.num_generations:  # a finished run resumed: its outputs are rewritten once
        _write_outputs_from_leader(out_dir, config, seeds, state, leader)
    return state


def _write_outputs_from_leader(out_dir: str, config: Config, seeds: Sequence[int], state: RunState,
                               leader: bool) -> None:
    """Gather the state on every process (to_host is a collective), then write on the leader."""
    host = state._replace(populations=to_host(state.populations), evaluated=to_host(state.evaluated),
                          fitness=to_host(state.fitness))
    if leader:
        write_outputs(out_dir, config, seeds, host)


# ----------------------------------------------------------------------------- CLI


def build_config(args) -> Config:
    """The config the command line asks for (raises UsageError naming the field)."""
    overrides = {"condition": args.cond}
    for flag, field in (("generations", "num_generations"), ("population", "population_size"),
                        ("parents", "num_parents"), ("childhood_steps", "childhood_steps"),
                        ("task_steps", "task_steps"), ("bins", "num_bins"), ("elites", "num_elites")):
        value = getattr(args, flag)
        if value is not None:
            overrides[field] = value
    overrides.update(parse_sets(args.set))
    try:
        return make_config(args.preset, **overrides)
    except ConfigError as error:
        raise UsageError(str(error)) from None


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m imrl_jax.evolve",
        description="Evolve one of the paper's conditions for several seeds at once "
                    "(Schembri, Mirolli & Baldassarre 2007).",
        formatter_class=HelpFormatter)
    p.add_argument("--cond", required=True, metavar="{" + ",".join(EVOLVED_CONDITIONS) + "}",
                   help="condition to evolve (SLE is not evolved)")
    p.add_argument("--seeds", type=int, default=1, help="number of independent evolutions (seeds)")
    p.add_argument("--first-seed", type=int, default=0, help="seed of the first evolution; the others follow")
    p.add_argument("--preset", default="paper", choices=sorted(PRESETS),
                   help="paper: the paper's rules at full scale; skills: full scale with the childhood study's choice "
                        "(docs/CHILDHOOD.md); extension: full scale with the learning extensions; small: reduced "
                        "lengths for quick CPU checks")
    p.add_argument("--generations", type=int, help="generations (default: the preset's; paper 100, small 10)")
    p.add_argument("--population", type=int, help="population size (default: the preset's; paper 50, small 20)")
    p.add_argument("--parents", type=int, help="best individuals that reproduce (default: the preset's; paper 10, small 4)")
    p.add_argument("--elites", type=int, help="parents copied unmutated (default: the preset's; paper 0)")
    p.add_argument("--childhood-steps", type=int, help="LE-LS childhood length (default: the preset's; paper 150000, small 15000)")
    p.add_argument("--task-steps", type=int, help="steps per adulthood task (default: the preset's; paper 100000, small 5000)")
    p.add_argument("--bins", type=int, help="bins of the per-task reward curves (default: the preset's; paper 100, small 10)")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help="set any scalar Config field, e.g. --set trace_lambda=0.9 (repeatable)")
    p.add_argument("--out", help="run directory (default: runs/COND)")
    p.add_argument("--resume", action="store_true", help="continue the run in --out from its latest checkpoint (--generations may grow: a finished run "
                        "is extended)")
    p.add_argument("--checkpoint-every", type=int, default=1, help="generations between checkpoints")
    p.add_argument("--keep", type=int, default=3, help="checkpoints kept (at least 1)")
    p.add_argument("--quiet", action="store_true", help="no progress line (for logs)")
    p.add_argument("--cpu-devices", type=int, default=0,
                   help="CPU devices to split the lanes over (0: one per core; ignored if XLA_FLAGS sets it)")
    p.add_argument("--coordinator", help="multi-host: coordinator address host:port (default: JAX_COORDINATOR_ADDRESS; none: one process)")
    p.add_argument("--num-processes", type=int, help="multi-host: number of processes (or JAX_NUM_PROCESSES)")
    p.add_argument("--process-id", type=int, help="multi-host: this process's id (or JAX_PROCESS_ID)")
    return p


def init_distributed(args) -> None:
    """Start jax.distributed when a coordinator is given by flag or environment.

    Must run before anything starts a JAX backend (``jax.devices()``, any computation).
    On CPU the processes' collectives (the sharded generation, ``process_allgather``,
    barriers) go over gloo/TCP. Raises UsageError on bad flags or a failed start.
    """
    coordinator = args.coordinator or os.environ.get("JAX_COORDINATOR_ADDRESS")
    if not coordinator:
        return
    num = args.num_processes if args.num_processes is not None else os.environ.get("JAX_NUM_PROCESSES")
    pid = args.process_id if args.process_id is not None else os.environ.get("JAX_PROCESS_ID")
    if num is None or pid is None:
        raise UsageError("--coordinator needs --num-processes and --process-id (or JAX_NUM_PROCESSES, JAX_PROCESS_ID)")
    try:
        num, pid = int(num), int(pid)
    except ValueError:
        raise UsageError(f"--num-processes/--process-id: expected integers, got {num!r} and {pid!r}") from None
    if num < 1 or not 0 <= pid < num:
        raise UsageError(f"--process-id: must be in 0..{num - 1} (--num-processes {num}), got {pid}")
    from jax._src import xla_bridge  # no public test for "backend started" that does not start it

    if xla_bridge.backends_are_initialized():
        raise UsageError("--coordinator: a JAX backend is already running in this process; "
                         "jax.distributed must start first (call main() in a fresh process)")
    # Not jax.default_backend() here: it would start the backend before jax.distributed.
    # The flag only matters to the CPU backend (gloo is also JAX 0.10's default there).
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    try:
        jax.distributed.initialize(coordinator, num, pid)
    except (RuntimeError, ValueError) as error:
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise UsageError(f"jax.distributed.initialize({coordinator!r}, {num}, {pid}) failed: {reason}") from None


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        if args.cond not in CONDITIONS:
            raise UsageError(f"--cond: unknown condition {args.cond!r} (choose from {', '.join(EVOLVED_CONDITIONS)})")
        if args.seeds < 1:
            raise UsageError("--seeds: must be at least 1")
        config = build_config(args)
        out_dir = args.out or os.path.join("runs", args.cond)
        if args.cpu_devices < 0:
            raise UsageError("--cpu-devices: must be 0 (one per core) or more")
        use_host_cores(args.cpu_devices or None)
        init_distributed(args)
        state = run(config, out_dir, range(args.first_seed, args.first_seed + args.seeds), resume=args.resume,
                    checkpoint_every=args.checkpoint_every, keep=args.keep, quiet=args.quiet)
    except user_errors() as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if jax.process_index() == 0:
        done = int(state.generation)
        best = state.history.best[done - 1]
        print(f"{config.condition}: generations 0-{done - 1} x {args.seeds} seed(s) done; best fitness of "
              f"generation {done - 1}: max over seeds {float(best.max()):.4f}, mean over seeds "
              f"{float(best.mean()):.4f} (per seed {', '.join(f'{b:.3f}' for b in best)}); outputs in {out_dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
