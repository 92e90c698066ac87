"""An evolution's state and files (section 2, "Genetic algorithm"; the evolve command's run directory).

Generation 0 of every seed, the per-generation record (``history.csv``: best, mean, std, the best's task
performances and evolved values), the outputs rewritten as a run goes (``fitness.png``, ``traits.png``,
``final_population.npz``), and the checks of a run directory before anything is written. The evolve command
(:mod:`imrl_jax.commands.evolve`) and its sweeps (:mod:`imrl_jax.commands.evolve_sweep`) share them.
"""

from __future__ import annotations

import csv
import io
import json
import os
import shlex
import time
from typing import Sequence

import jax
import numpy as np

from imrl_jax.evolution import search
from imrl_jax.runs.checkpoint import History, RunState, empty_history, git_commit
from imrl_jax.runs.cli import MAX_KEY, UsageError
from imrl_jax.config import Config, make_config
from imrl_jax.evolution.devices import make_mesh, replicated, to_global, to_host
from imrl_jax.runs.events import check_log
from imrl_jax.evolution.ga import GA, init_population
from imrl_jax.agent.networks import trait_names
from imrl_jax.runs.rundir import (RunDirError, RunWriteError, entries, not_empty, read_config, read_json, write_atomic,
                             write_errno)
from imrl_jax.evolution.strategies import GA_RECORD

# ----------------------------------------------------------------------------- state


def initial_state(config: Config, seeds: Sequence[int], sharding, strategy=None, mesh=None) -> RunState:
    """Generation 0 of every seed (drawn from the seed's own key).

    The paper's GA (``strategy`` None or a GA) draws the population uniformly; another strategy is
    initialised with the same key and asked for generation 0 with the generations' keys (its state,
    replicated over ``mesh``, is the run's ``search``).
    """
    keys = search.seed_keys(seeds)
    init_keys = jax.vmap(lambda k: jax.random.fold_in(k, 0))(keys)
    key_data = np.asarray(jax.random.key_data(keys))
    search_state = ()
    if strategy is None or isinstance(strategy, GA):
        populations = np.asarray(jax.vmap(lambda k: init_population(k, config))(init_keys))
    else:
        params = strategy.default_params()
        states = jax.vmap(lambda k: strategy.init(k, params))(init_keys)
        populations, states = jax.jit(jax.vmap(lambda k, s: search.ask(k, strategy, s, params, 0)))(
            search.evolution_keys(key_data), states)
        populations = np.asarray(populations, np.float32)
        search_state = jax.tree.map(lambda x: to_global(np.asarray(x), replicated(mesh or make_mesh())), states)
    shape = populations.shape
    history = empty_history(config.num_generations, len(seeds), config.num_tasks)
    names = trait_names(config)
    traits = np.full((config.num_generations, len(seeds), len(names), 2), np.nan, np.float32) if names else ()
    return RunState(
        generation=np.asarray(0, np.int32),
        populations=to_global(populations, sharding),
        evaluated=to_global(np.zeros(shape, np.float32), sharding),
        fitness=to_global(np.zeros(shape[:2], np.float32), sharding),
        key_data=key_data,
        history=history,
        search=search_state,
        traits=traits,
    )


def record_traits(traits: np.ndarray, generation: int, fitness: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Traits (G, S, T, 2) with generation's population mean (``[..., 0]``) and best's (``[..., 1]``) of ``values``
    (S, P, T) written in."""
    traits = np.array(traits)
    best = np.argmax(fitness, axis=1)
    traits[generation, :, :, 0] = values.mean(1)
    traits[generation, :, :, 1] = values[np.arange(len(best)), best]
    return traits


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


def history_csv(history: History, generations: int, seeds: Sequence[int], traits=(), names: Sequence[str] = ()) -> str:
    """The history of the finished generations as CSV text; with ``traits`` (G, S, T, 2) of ``names``, the
    population mean (``mean_NAME``) and the best individual's value (``best_NAME``) of each, too."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    num_tasks = history.best_performance.shape[-1]
    writer.writerow(["generation", "seed", "best", "mean", "std"] + [f"best_task{i + 1}" for i in range(num_tasks)]
                    + [f"{which}_{name}" for name in names for which in ("mean", "best")])
    for g in range(generations):
        for s, seed in enumerate(seeds):
            writer.writerow([g, seed] + [f"{float(history.best[g, s]):.6f}", f"{float(history.mean[g, s]):.6f}",
                                         f"{float(history.std[g, s]):.6f}"]
                            + [f"{float(p):.6f}" for p in history.best_performance[g, s]]
                            + [f"{float(v):.6g}" for t in range(len(names)) for v in traits[g, s, t]])
    return out.getvalue()


def write_outputs(out_dir: str, config: Config, seeds: Sequence[int], state: RunState) -> None:
    """Rewrite history.csv, fitness.png and final_population.npz from a state."""
    from imrl_jax.analysis.charts import plot_fitness
    from imrl_jax.analysis.plotting import save

    done = int(state.generation)
    names = trait_names(config)
    write_atomic(os.path.join(out_dir, "history.csv"),
                 history_csv(state.history, done, seeds, state.traits, names).encode())
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
        if names:
            from imrl_jax.analysis.charts import plot_traits

            save(plot_traits(config, names, np.asarray(state.traits)[:done],
                             title=f"{config.condition}: evolved values per generation, mean over {len(seeds)} "
                                   f"seed(s){scale}"),
                 os.path.join(out_dir, "traits.png"))


def _is_paper_scale(config: Config) -> bool:
    paper = make_config("paper", condition=config.condition)
    return all(getattr(config, f) == getattr(paper, f) for f in
               ("childhood_steps", "task_steps", "population_size", "num_generations", "num_parents"))


# ----------------------------------------------------------------------------- run


def check_run_dir(out_dir: str, config: Config, seeds: Sequence[int], resume: bool,
                  search_record: dict | None = None) -> None:
    """Refuse to write into anything but a new or empty directory or (resuming) a run of this config and search
    strategy (``search_record``, :func:`imrl_jax.evolution.strategies.describe`; the GA if None). Raises UsageError
    (RunDirError for a directory holding something else)."""
    config_path = os.path.join(out_dir, "config.json")
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise UsageError(f"--out: {out_dir} is not a directory")
    exists = os.path.exists(config_path)
    if exists and not resume:
        raise UsageError(f"{out_dir} already holds a run (config.json); pass --resume to continue it "
                         f"or choose another --out")
    if resume and not exists:
        raise UsageError(f"--resume: {out_dir} holds no run to resume (no config.json)")
    found = [] if exists else entries(out_dir)
    if found:  # its files could have the names of a run's outputs
        raise not_empty(out_dir, "run", found, missing="config.json")
    if exists:
        saved_config, saved_seeds = read_config(out_dir)
        if saved_seeds != list(seeds):
            raise UsageError(f"--resume: seeds {list(seeds)} differ from the run's {saved_seeds}")
        saved_search, asked = read_search(out_dir), search_record or GA_RECORD
        if saved_search != asked:
            raise UsageError(f"--strategy: {out_dir} was evolved with {_strategy_text(saved_search)}, not "
                             f"{_strategy_text(asked)}; resume it with its own (leave out --strategy)")
        differing = [name for name in saved_config.model_differences(config)
                     if not (name == "num_generations" and config.num_generations > saved_config.num_generations)]
        if differing:  # a run may be extended: its generations go on from the last one done
            changes = "; ".join(_difference(name, config, saved_config) for name in differing)
            raise UsageError(f"--resume: the config differs from the run's in {out_dir}: {changes}")


def _difference(name: str, config: Config, saved: Config) -> str:
    """One differing field, in words (a task set by how many of its tasks differ, not every coordinate)."""
    if name == "tasks":
        differ = sum(a != b for a, b in zip(config.tasks, saved.tasks)) + abs(len(config.tasks) - len(saved.tasks))
        return f"tasks: {differ} of the run's {len(saved.tasks)} tasks differ (--task-set)"
    return (f"{name} is {getattr(config, name)!r} but the run used {getattr(saved, name)!r}"
            + (" (a resumed run may only grow it)" if name == "num_generations" else ""))


def read_search(out_dir: str) -> dict:
    """The search strategy a run records in its config.json (the paper's GA if it records none; raises RunDirError
    naming the file if it records something else than a strategy's name and settings)."""
    path = os.path.join(out_dir, "config.json")
    saved = read_json(path, "")
    found = saved.get("search", GA_RECORD) if isinstance(saved, dict) else None
    if not (isinstance(found, dict) and isinstance(found.get("strategy"), str)
            and isinstance(found.get("settings"), dict)):
        raise RunDirError(f"{path} is unreadable (its search is {found!r}, not a strategy and its settings)")
    return found


def _strategy_text(record: dict) -> str:
    settings = ", ".join(f"{k}={v:g}" for k, v in sorted(record["settings"].items()))
    return record["strategy"] + (f" ({settings})" if settings else "")


def extend_config_json(out_dir: str, config: Config) -> None:
    """Record a grown ``num_generations`` in the run's config.json (with when it grew from what)."""
    path = os.path.join(out_dir, "config.json")
    info = read_json(path, "")
    old = int(info["config"]["num_generations"])
    if old == config.num_generations:
        return
    info["config"]["num_generations"] = config.num_generations
    info.setdefault("extended", []).append(dict(num_generations=[old, config.num_generations],
                                                 at=time.strftime("%Y-%m-%dT%H:%M:%S%z"), git_commit=git_commit()))
    write_atomic(path, json.dumps(info, indent=2).encode())


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during the generations: how far the run got (the command reports it in one line, exit code 130)."""

    def __init__(self, out_dir: str, done: int, checkpointed: int, total: int):
        super().__init__(f"interrupted with {done} of {total} generations done, {checkpointed} checkpointed")
        self.out_dir, self.done, self.checkpointed, self.total = out_dir, done, checkpointed, total


def write_failed(error: BaseException, what: str, out_dir: str, generation: int, checkpointed: int) -> RunWriteError:
    """The one-line report of a write the user can fix (a full disk, an unwritable file)."""
    where = getattr(error, "filename", None) or what
    reason = getattr(error, "strerror", None) or os.strerror(write_errno(error))
    return RunWriteError(f"cannot write {where} ({reason}) after generation {generation - 1} ({checkpointed} "
                         f"generation(s) checkpointed); free space or fix permissions, then resume with: "
                         f"{resume_command(out_dir)}")


def resume_command(out_dir: str) -> str:
    """The command line that resumes the run in ``out_dir``."""
    return f"python -m imrl_jax.evolve --resume --out {shlex.quote(out_dir)}"


def check_run_options(config: Config, seeds: Sequence[int], checkpoint_every: int, keep: int,
                      log: str | None, out_dir: str | None = None) -> list[int]:
    """The seeds as a list, once the options of a run are good (raises UsageError naming the option; with ``out_dir``,
    a ``--log`` whose folder there cannot be made or written too)."""
    if not config.spec.evolved:
        raise UsageError(f"--cond: {config.condition} is not evolved (it learns each task from scratch); "
                         f"test it with: python -m imrl_jax.learning_test --cond {config.condition} --out DIR")
    seeds = [int(s) for s in seeds]
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise UsageError("--seeds: need at least one seed, all distinct and non-negative")
    if max(seeds) > MAX_KEY:
        raise UsageError(f"--seeds: every seed must be below 2^32 (a uint32 key; got {max(seeds):,})")
    if checkpoint_every < 1:
        raise UsageError("--checkpoint-every: must be at least 1")
    if keep < 1:
        raise UsageError("--keep: must be at least 1 (a run keeps its latest checkpoint to resume from)")
    try:
        check_log(log, out_dir)
    except ValueError as error:
        raise UsageError(str(error)) from None
    return seeds


#: Characters of history.csv a number takes (its digits and comma), and bytes of memory each character takes while
#: the text is made (io.StringIO's buffer of 4-byte characters, the text, its encoding).
CSV_CHARACTERS, CSV_BYTES = 12, 6


def history_bytes(config: Config, num_seeds: int) -> int:
    """Bytes of host memory a run's record of every generation takes: its history and traits (RunState.history,
    .traits: float32, held about three times while recorded and saved) and history.csv's text made from them."""
    numbers = 3 + config.num_tasks + 2 * len(trait_names(config))  # best, mean, std, each task's, each trait's two
    row = 3 * 4 * numbers + CSV_BYTES * CSV_CHARACTERS * (2 + numbers)  # and the generation's and seed's columns
    return config.num_generations * num_seeds * row


def generations_recorded(out_dir: str) -> int:
    """The generations a run's final_population.npz says are done (0 if it has none or it cannot be read)."""
    try:
        with np.load(os.path.join(out_dir, "final_population.npz")) as data:
            return int(data["generation"])
    except (OSError, ValueError, KeyError):
        return 0
