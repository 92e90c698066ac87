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
``final_population.npz`` and ``checkpoints/`` (and, for a condition evolving values besides weights,
their per-generation mean and best's in ``history.csv`` and ``traits.png``); all are rewritten as the
run goes. It must be
new or empty (or, with ``--resume``, the run itself), and one process writes it at a time
(``.lock``). ``--resume --out RUN`` is enough: the run's own config and seeds are used.

As every command (:mod:`imrl_jax.runs.cli`), it plans first (:func:`plan_from_args`: every option, file and the
memory checked, nothing written), then carries the plan out (``cli.execute``): a resume's checkpoint is read
after the lock and before anything is written.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import time
from typing import NamedTuple, Sequence

import jax
import numpy as np

import imrl_jax
from imrl_jax.runs.checkpoint import Checkpointer, RunState, _silence_failed_reads, git_commit
from imrl_jax.runs import cli
from imrl_jax.commands import evolve_sweep
from imrl_jax.agent import kernel_choice
from imrl_jax.runs.cli import UsageError, exit_codes, parse_sets, user_errors
from imrl_jax.evolution.devices import (check_memory, init_distributed, make_mesh, memory_needed, population_sharding, replicated,
                              sharded_axis, to_global, to_host, use_host_cores)
from imrl_jax.config import Config
from imrl_jax.evolution import search
from imrl_jax.evolution.ga import GA, make_generation
from imrl_jax.agent.lifetime import live
from imrl_jax.agent.networks import trait_names, traits
from imrl_jax.runs.events import add_log, make_log
# parser, build_config and build_strategy: evolve's names for them (the study tables build runs' keys with them).
from imrl_jax.commands.evolve_options import build_config, build_strategy, check_condition, check_sizes, parser
from imrl_jax.runs.progress import Progress, cost_line
from imrl_jax.runs.rundir import (RunDirError, check_unlocked, check_writable, lock_run_dir, make_dir,
                             read_config, write_atomic, write_errno)
# history_csv, initial_state, seed_keys, evolution_keys and record_traits: evolve's names for them (notebooks use them).
from imrl_jax.evolution.search import evolution_keys, seed_keys  # noqa: F401
from imrl_jax.runs.run_state import (RunInterrupted, check_run_dir, check_run_options,  # noqa: F401
                                     extend_config_json, generations_recorded, history_bytes, history_csv,
                                     initial_state, read_search, record, record_traits, resume_command, write_failed,
                                     write_outputs)
from imrl_jax.evolution.strategies import GA_RECORD, describe

__all__ = ["UsageError", "parse_sets", "write_atomic", "parser", "build_config", "build_strategy",  # re-exported
           "history_csv", "initial_state", "seed_keys", "evolution_keys", "record_traits",  # re-exported
           "run", "plan", "RunPlan", "plan_from_args", "make_step", "main"]

# ----------------------------------------------------------------------------- run


def run(config: Config, out_dir: str, seeds: Sequence[int] = (0,), *, strategy=None, resume: bool = False,
        checkpoint_every: int = 1, keep: int = 3, quiet: bool = False, warnings: Sequence[str] = (),
        notes: Sequence[str] = (), registered: Sequence[str] = (), log: str | None = None) -> RunState:
    """Evolve ``config.condition`` for every seed into ``out_dir``; return the final state.

    ``strategy`` is the search (:mod:`imrl_jax.evolution.strategies`; default the paper's GA). The directory is
    locked for the whole run (:func:`imrl_jax.runs.rundir.lock_run_dir`). ``warnings`` are printed once the
    checks pass, ``notes`` too unless ``quiet``. ``registered``: the ``--register`` rows, recorded in config.json.
    ``log="tensorboard"``: the progress is also written for TensorBoard under ``out_dir/tensorboard``.
    Every check is done first (:func:`plan`), then the run.
    """
    return plan(config, out_dir, seeds, strategy=strategy, resume=resume, checkpoint_every=checkpoint_every, keep=keep,
                quiet=quiet, warnings=warnings, notes=notes, registered=registered, log=log).run()


def plan(config: Config, out_dir: str, seeds: Sequence[int] = (0,), *, strategy=None, resume: bool = False,
         checkpoint_every: int = 1, keep: int = 3, quiet: bool = False, warnings: Sequence[str] = (),
         notes: Sequence[str] = (), registered: Sequence[str] = (), log: str | None = None) -> "RunPlan":
    """Every check of :func:`run` (options, the run directory, the memory), nothing written: its plan."""
    config, kernel_note = kernel_choice.resolve(config)  # "auto" made xla or pallas here: config.json records it
    notes = (*notes, *filter(None, [kernel_note]))
    strategy = GA(config) if strategy is None else strategy
    seeds = check_run_options(config, seeds, checkpoint_every, keep, log, out_dir)
    check_writable(out_dir)
    check_unlocked(out_dir)  # a live writer is named before anything about what it is writing
    check_run_dir(out_dir, config, seeds, resume, describe(strategy))
    check_memory(config, len(seeds) * config.population_size * config.lives_per_fitness // jax.process_count(),
                 f"evolving {len(seeds)} seed(s) x {config.population_size} individuals",
                 host_bytes=history_bytes(config, len(seeds)))
    return RunPlan(config, out_dir, seeds, strategy, resume, checkpoint_every, keep, quiet, tuple(warnings),
                   tuple(notes), tuple(registered), log)


class RunPlan(NamedTuple):
    """A checked evolution (:func:`plan`); :meth:`execute` carries it out."""

    config: Config
    out_dir: str
    seeds: list[int]
    strategy: object
    resume: bool
    checkpoint_every: int
    keep: int
    quiet: bool
    warnings: tuple
    notes: tuple
    registered: tuple
    log: str | None

    def execute(self) -> int:
        """Run, then say where the outputs are; the exit code."""
        state = self.run()
        if jax.process_index() == 0:
            done = int(state.generation)
            best = state.history.best[done - 1]
            print(f"{self.config.condition}: generations 0-{done - 1} x {len(self.seeds)} seed(s) done; best fitness "
                  f"of generation {done - 1}: max over seeds {float(best.max()):.4f}, mean over seeds "
                  f"{float(best.mean()):.4f} (per seed {', '.join(f'{b:.3f}' for b in best)}); outputs in "
                  f"{self.out_dir}")
        return 0

    def run(self) -> RunState:
        """Lock, check again, restore a resumed run (read only), then write and evolve; the final state."""
        config, out_dir, seeds, strategy, resume = self.config, self.out_dir, self.seeds, self.strategy, self.resume
        multihost = jax.process_count() > 1
        if multihost:  # every process checks before the leader writes
            from jax.experimental import multihost_utils

            multihost_utils.sync_global_devices("imrl_jax.evolve: run directory checked")
        leader = jax.process_index() == 0
        quiet = self.quiet or not leader
        mesh = make_mesh()
        sharding = population_sharding(mesh, len(seeds), config.population_size)
        with contextlib.ExitStack() as stack:
            failure = None
            if leader:
                try:
                    make_dir(out_dir)
                    stack.enter_context(lock_run_dir(out_dir))
                    check_run_dir(out_dir, config, seeds, resume, describe(strategy))  # again, locked
                    if not resume:  # first, so that the directory is this run's from the start
                        info = {"config": config.to_dict(), "seeds": seeds, "search": describe(strategy),
                                **({"register": list(self.registered)} if self.registered else {}),
                                "version": imrl_jax.__version__,
                                "git_commit": git_commit(), "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                                "devices": len(jax.devices()), "processes": jax.process_count(),
                                "sharded_axis": sharded_axis(sharding)}
                        write_atomic(os.path.join(out_dir, "config.json"), json.dumps(info, indent=2).encode())
                except user_errors() as error:
                    failure = error
                except OSError as error:
                    if write_errno(error) is None:
                        raise
                    failure = RunDirError(f"--out: cannot write {error.filename or out_dir} ({error.strerror})")
            if multihost:  # the others stop with the leader (else they would wait for it in a collective)
                from jax.experimental import multihost_utils

                ok = multihost_utils.broadcast_one_to_all(np.asarray(failure is None, np.int32))
                if not leader and not int(ok):
                    raise RunDirError(f"--out: process 0 could not take {out_dir} (its error says why)")
                if not leader:
                    make_dir(out_dir)
            if failure is not None:
                raise failure
            for line in [*self.warnings, *([] if self.quiet else self.notes)] if leader else []:
                print(line, file=sys.stderr, flush=True)
            _silence_failed_reads()  # Ctrl-C in a save: orbax's threads end without their tracebacks
            events = stack.enter_context(contextlib.closing(make_log()))  # its --log sink added once restored
            progress = Progress(config.num_generations, quiet=quiet, first_index=0, log=events)
            state = initial_state(config, seeds, sharding, strategy, mesh)
            checkpointer = stack.enter_context(contextlib.closing(
                Checkpointer(os.path.join(out_dir, "checkpoints"), keep=self.keep)))
            first = 0
            if resume:  # read only: a refusal here leaves every file as it was
                state, progress = _restore(config, out_dir, seeds, strategy, state, checkpointer, progress, events,
                                           quiet)
                first = int(state.generation)
                if leader and first:
                    extend_config_json(out_dir, config)
            add_log(events, self.log if leader else None, out_dir, first)
            return _evolve(config, out_dir, seeds, state, sharding, mesh, checkpointer, strategy, progress,
                           checkpoint_every=self.checkpoint_every, leader=leader)


def _restore(config: Config, out_dir: str, seeds: list[int], strategy, state: RunState, checkpointer: Checkpointer,
             progress: Progress, events, quiet: bool) -> tuple[RunState, Progress]:
    """A resumed run's state from its latest good checkpoint (generation 0 if it has none) and its progress line;
    nothing written (raises UsageError if no checkpoint can be read or it is another run's)."""
    restored = checkpointer.restore_latest(state, warn=lambda text: progress.message(f"warning: {text}"))
    if restored is None:
        if checkpointer.steps():
            raise UsageError(f"--resume: no readable checkpoint in {checkpointer.directory}")
        recorded = generations_recorded(out_dir)
        if recorded:  # its checkpoints were removed: said even with --quiet, the generations are redone
            progress.message(f"warning: {checkpointer.directory} holds no checkpoint, but {out_dir} records "
                             f"{recorded} generation(s) done: starting again from generation 0 (the same "
                             f"generations again, bitwise)")
        else:
            progress.note(f"no checkpoint in {checkpointer.directory} yet: starting from generation 0")
        return state, progress
    state, saved_meta = restored
    made_by = saved_meta.get("search", GA_RECORD)
    if made_by != describe(strategy):
        raise UsageError(f"--strategy: the checkpoint was made by {made_by}, not {describe(strategy)}")
    if not np.array_equal(state.key_data, np.asarray(jax.random.key_data(seed_keys(seeds)))):
        raise UsageError("--resume: the checkpoint's keys do not match the seeds")
    if int(state.generation) > config.num_generations:  # only if config.json was edited by hand
        raise UsageError(f"--resume: config field num_generations is {config.num_generations} but "
                         f"{int(state.generation)} generations are done")
    progress = Progress(config.num_generations, done=int(state.generation), quiet=quiet, first_index=0, log=events,
                        elapsed=float(saved_meta.get("elapsed_seconds", 0.0)))
    progress.note(f"resuming {out_dir} after generation {int(state.generation) - 1} "
                  f"({int(state.generation)} of {config.num_generations} done; checkpoint of commit "
                  f"{saved_meta.get('git_commit', 'unknown')[:12]})")
    return state, progress


def _evolve(config: Config, out_dir: str, seeds: list[int], state: RunState, sharding, mesh,
            checkpointer: Checkpointer, strategy, progress: Progress, *, checkpoint_every: int,
            leader: bool) -> RunState:
    """The generations of :func:`run` after its checks and restore, from ``state``'s generation.

    Ctrl-C raises :class:`RunInterrupted`; a write the user can fix, :class:`RunWriteError`.
    """
    meta = {"config": config.to_dict(), "seeds": seeds, "search": describe(strategy)}
    checkpointed = int(state.generation)
    try:
        generation = make_step(config, strategy, sharding)
        keys = to_global(evolution_keys(state.key_data), replicated(mesh))
        params = config.learning_params()
        lives = len(seeds) * config.population_size * config.lives_per_fitness
        lane_steps = lives * config.lifetime_steps
        first = int(state.generation)
        if first < config.num_generations:  # what it will cost, before the compilation it waits for
            progress.note(cost_line(f"evolving {config.condition}: {len(seeds)} seed(s) x {config.population_size} "
                                    f"individuals x {config.num_generations - first} generation(s)", lives, lane_steps,
                                    config.num_generations - first, jax.default_backend(),
                                    memory_needed(config, lives, jax.device_count(), history_bytes(config, len(seeds))),
                                    world=config.world)
                          + f"; step_kernel={kernel_choice.chosen(config)}")
            progress.note("compiling the generation (its first line comes once it is compiled and run) ...")
        if trait_names(config):
            trait_values = jax.jit(jax.vmap(jax.vmap(lambda genome: traits(config, genome))))
        for g in range(first, config.num_generations):
            start = time.perf_counter()
            evaluated = state.populations
            populations, search_state, stats = generation(keys, params, evaluated, state.search, g)
            fitness, performance = to_host(stats.fitness), to_host(stats.performance)
            seconds = time.perf_counter() - start
            recorded = state.traits
            if trait_names(config):
                recorded = record_traits(state.traits, g, fitness, to_host(trait_values(evaluated)))
            state = RunState(np.asarray(g + 1, np.int32), populations, evaluated, stats.fitness, state.key_data,
                             record(state.history, g, fitness, performance), search_state, recorded)
            best = fitness.max(1)
            progress.update(g + 1, float(best.max()), float(fitness.mean()), lane_steps / seconds,
                            scores=f"best fitness: max over seeds {best.max():.4f}, mean over seeds {best.mean():.4f}")
            if (g + 1) % checkpoint_every == 0 or g + 1 == config.num_generations:
                try:  # every process: orbax saves collectively
                    checkpointer.save(state, {**meta, "elapsed_seconds": round(progress.elapsed(), 3)})
                except Exception as error:  # noqa: BLE001 - orbax wraps the OS error in its own
                    if write_errno(error) is None:
                        raise
                    raise write_failed(error, os.path.join(checkpointer.directory, str(g + 1)), out_dir, g + 1,
                                        checkpointed) from None
                checkpointed = g + 1
                _write_outputs_from_leader(out_dir, config, seeds, state, leader, checkpointed)
        if first == config.num_generations:  # a finished run resumed: its outputs are rewritten once
            progress.note(f"{out_dir} is finished ({first} of {first} generations): its outputs are rewritten; "
                          f"--generations N (more than {first}) extends it")
            _write_outputs_from_leader(out_dir, config, seeds, state, leader, checkpointed)
    except KeyboardInterrupt:
        raise RunInterrupted(out_dir, int(state.generation), checkpointed, config.num_generations) from None
    return state


def make_step(config: Config, strategy, sharding):
    """The jitted generation ``step(keys, params, populations, search_state, index)`` of ``strategy``.

    It returns the next populations, the next search state and each seed's fitness and performance.
    The paper's GA keeps its own step (:func:`imrl_jax.evolution.ga.make_generation`, bitwise as it always was;
    its state is the populations); another strategy runs :func:`imrl_jax.evolution.search.make_generation`.
    """
    if isinstance(strategy, GA):
        ga_step = make_generation(config, sharding)

        def step_ga(keys, params, populations, search_state, index):
            children, stats = ga_step(keys, params, populations, index)
            return children, search_state, stats

        return step_ga
    step = search.make_generation(strategy, lambda k, p, g: live(k, config, p, g), config.lives_per_fitness, sharding,
                                  kernel=kernel_choice.chosen(config) == "pallas")  # said: not found by tracing
    search_params = strategy.default_params()
    return lambda keys, params, populations, search_state, index: step(keys, params, populations, search_state,
                                                                        search_params, index)


def _write_outputs_from_leader(out_dir: str, config: Config, seeds: Sequence[int], state: RunState,
                               leader: bool, checkpointed: int) -> None:
    """Gather the state on every process (to_host is a collective), then write on the leader."""
    host = state._replace(populations=to_host(state.populations), evaluated=to_host(state.evaluated),
                          fitness=to_host(state.fitness))
    if leader:
        try:
            write_outputs(out_dir, config, seeds, host)
        except OSError as error:
            if write_errno(error) is None:
                raise
            raise write_failed(error, out_dir, out_dir, int(state.generation), checkpointed) from None


def plan_from_args(args) -> RunPlan | evolve_sweep.SweepPlan:
    """The plan of a parsed command line: a run or a sweep, every check done, nothing written (raises a user error)."""
    check_sizes(args)
    registered = cli.register(args.register)
    check_condition(args)
    cli.check_cpu_devices(args.cpu_devices)
    cli.check_out(args.out)
    # Before anything starts JAX (the task set's checks, a strategy's arrays): later, neither takes effect.
    use_host_cores(args.cpu_devices or None)
    init_distributed(args.coordinator, args.num_processes, args.process_id)
    out_dir = args.out or os.path.join("runs", args.cond + ("-sweep" if args.sweep else ""))
    if args.sweep or (args.resume and evolve_sweep.is_sweep(out_dir)):
        return evolve_sweep.plan_from_args(args, out_dir, registered, build_config)
    if args.zip:
        raise UsageError("--zip: only with --sweep")
    saved = None
    if args.resume:
        if not os.path.exists(os.path.join(out_dir, "config.json")):
            raise UsageError(f"--resume: {out_dir} holds no run to resume (no config.json)")
        saved = read_config(out_dir)
    config, seeds = build_config(args, saved)
    strategy = build_strategy(args, config, read_search(out_dir) if args.resume else None)
    notes = cli.ignored_notes(config, parse_sets(args.set))
    return plan(config, out_dir, seeds, strategy=strategy, resume=args.resume, checkpoint_every=args.checkpoint_every,
                keep=args.keep, quiet=args.quiet, warnings=cli.device_warnings(config, args.cpu_devices), notes=notes,
                registered=registered, log=args.log)


def interrupted(stop: KeyboardInterrupt, out_dir: str | None) -> int:
    """Ctrl-C in one line: how far the run got and how to resume it; exit code 130."""
    if isinstance(stop, RunInterrupted):
        where = (f"in generation {stop.done} ({stop.done} of {stop.total} done, {stop.checkpointed} checkpointed)"
                 if stop.done < stop.total else "after the last generation")
    else:
        where = "before the first generation"
    started = out_dir is not None and any(os.path.exists(os.path.join(out_dir, name))
                                          for name in ("config.json", evolve_sweep.SWEEP_FILE))
    print(f"interrupted {where}; " + (f"resume with: {resume_command(out_dir)}" if started else "nothing to resume"),
          file=sys.stderr)
    return 130


@exit_codes
def main(argv=None) -> int:
    checked = None
    try:
        checked = plan_from_args(parser().parse_args(argv))
        return cli.execute(checked)
    except KeyboardInterrupt as stop:
        return interrupted(stop, None if checked is None else checked.out_dir)


if __name__ == "__main__":
    sys.exit(main())
