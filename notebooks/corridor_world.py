"""A world of one's own (docs/WORLDS.md): a corridor of coloured cells, in one module.

A row of cells, each red, green or blue (``CorridorSettings.cells``: ``"rrrrggggbbbb"``, a segment of each colour).
The agent stands on a cell facing left or right and sees its own cell and the cells ahead, each as a colour one-hot
(nothing past an end). It acts by one of two actions: step forward (not past an end) or turn round. A task starts in
the middle of one colour, facing right, and ends on one end of the corridor: the left end (red's) or the right end
(blue's), so it is solved by following one colour, then the next ("from green to the red end": turn round, follow
green, then red). Two tasks start on each colour and part there, as the paper's pairs part at their first junction.

Every method of imrl_jax.world.base's ``World`` and ``Env`` is here, with ``lax``-friendly ``jnp`` code only: a
task's params and the state are NamedTuples of arrays, so that a life can be jitted and vmapped. Register it with
``worlds.register("corridor", "corridor_world")`` (the module's path: ``make_world`` reads the settings).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.world.base import DISCRETE, Actions, Events

COLOURS = "rgb"  # one input per colour per cell seen
FORWARD, TURN = 0, 1  # the actions, by index


@dataclasses.dataclass(frozen=True)
class CorridorSettings:
    """The world's own settings (a config's ``world_settings``)."""

    cells: str = "rrrrggggbbbb"  # each cell's colour, left to right: three segments, one per colour
    view: int = 3  # cells seen: the agent's own and view - 1 ahead
    trial_timeout: int = 0  # steps of a trial; 0: the config's trial_timeout
    stuck_steps: int = 20  # with respawns: steps in a row without moving before a random start

    def __post_init__(self):
        if set(self.cells) - set(COLOURS) or len(self.cells) < 3 or not 1 <= self.view <= len(self.cells):
            raise ValueError(f"CorridorSettings: cells must be 3 or more of {COLOURS!r} and view from 1 to their "
                             f"number, got {self.cells!r} and {self.view}")


class CorridorTask(NamedTuple):
    """A task's params (World.task): where its trials start and the cell to reach (-1 in childhood: none)."""

    start: jnp.ndarray  # () int32, a cell
    facing: jnp.ndarray  # () int32, +1 right or -1 left
    goal: jnp.ndarray  # () int32, a cell


class CorridorState(NamedTuple):
    """The environment's state (any pytree of arrays): the agent's cell and facing, and two counters."""

    position: jnp.ndarray  # () int32
    facing: jnp.ndarray  # () int32
    trial_step: jnp.ndarray  # steps since the trial started
    still: jnp.ndarray  # steps in a row without moving (with respawns)


def task_table(s: CorridorSettings) -> CorridorTask:
    """Every task's params, (tasks,) each: from the middle of each colour segment facing right, to each end."""
    runs = [i for i in range(len(s.cells)) if i == 0 or s.cells[i] != s.cells[i - 1]] + [len(s.cells)]
    starts = [(a + b - 1) // 2 for a, b in zip(runs, runs[1:])]
    rows = [(start, 1, goal) for start in starts for goal in (0, len(s.cells) - 1)]
    return CorridorTask(*(np.asarray(column, np.int32) for column in zip(*rows)))


@dataclasses.dataclass(frozen=True)
class CorridorEnv:
    """One phase's environment (World.make_env): a task's trials, or the open corridor of childhood."""

    settings: CorridorSettings
    trial_timeout: int
    has_target: bool = True
    respawn: bool = False

    def at(self, position, facing) -> CorridorState:
        """The agent on ``position`` facing ``facing``, a trial just started."""
        return CorridorState(jnp.asarray(position, jnp.int32), jnp.asarray(facing, jnp.int32), jnp.int32(0),
                             jnp.int32(0))

    def spawn(self, uniforms: jnp.ndarray) -> CorridorState:
        """A random cell and facing from two uniform numbers in [0, 1) (World.num_spawn_draws = 2)."""
        n = len(self.settings.cells)
        return self.at(jnp.minimum((uniforms[0] * n).astype(jnp.int32), n - 1), jnp.where(uniforms[1] < 0.5, -1, 1))

    def reset(self, key: jax.Array, params: CorridorTask, dtype=jnp.float32) -> CorridorState:
        """Env.reset: the task's start; without a target (childhood) a random one drawn from ``key``."""
        if self.has_target:
            return self.at(params.start, params.facing)
        return self.spawn(jax.random.uniform(key, (2,)))

    def observe(self, state: CorridorState) -> jnp.ndarray:
        """Env.observe: the cells seen (own first), each a one-hot over COLOURS; zeros past an end."""
        n, codes = len(self.settings.cells), jnp.asarray([COLOURS.index(c) for c in self.settings.cells])
        seen = state.position + state.facing * jnp.arange(self.settings.view)
        inside = (seen >= 0) & (seen < n)
        onehot = (codes[jnp.clip(seen, 0, n - 1)][:, None] == jnp.arange(len(COLOURS))) & inside[:, None]
        return onehot.reshape(-1).astype(jnp.float32)

    def transition(self, state: CorridorState, action: jnp.ndarray, params: CorridorTask, spawn=None):
        """Env.transition: step forward or turn round; with respawns a random start after ``stuck_steps`` steps
        without moving; with a target, standing on the goal (a reach) or the timeout starts the trial again."""
        ahead = state.position + state.facing
        moves = (action == FORWARD) & (ahead >= 0) & (ahead < len(self.settings.cells))
        new = CorridorState(jnp.where(moves, ahead, state.position),
                            jnp.where(action == TURN, -state.facing, state.facing),
                            state.trial_step + 1, jnp.where(moves, 0, state.still + 1))
        reached = respawned = timeout = jnp.bool_(False)
        if self.has_target:
            reached = new.position == params.goal
        if self.respawn:
            respawned = new.still >= self.settings.stuck_steps
            new = jax.tree.map(lambda fresh, now: jnp.where(respawned, fresh, now), self.spawn(spawn), new)
        if self.has_target:
            timeout = ~reached & (new.trial_step >= self.trial_timeout)
            start = self.at(params.start, params.facing)._replace(still=new.still)
            new = jax.tree.map(lambda s, now: jnp.where(reached | timeout, s, now), start, new)
        return new, Events(reached, timeout, respawned)


@dataclasses.dataclass(frozen=True)
class Corridor:
    """The world (imrl_jax.world.base.World): what is observed, how one acts, the tasks, an Env per phase."""

    settings: CorridorSettings = CorridorSettings()
    name: ClassVar[str] = "corridor"
    num_spawn_draws: ClassVar[int] = 2  # a respawn's cell and facing

    def num_inputs(self, config=None) -> int:
        """World.num_inputs: cells seen x colours (3 x 3 = 9 by default)."""
        return self.settings.view * len(COLOURS)

    def actions(self, config=None) -> Actions:
        """World.actions: one of two, forward or turn round."""
        return Actions(DISCRETE, 2)

    def num_tasks(self, config=None) -> int:
        """World.num_tasks: two per colour segment (six by default, the config's count)."""
        return len(task_table(self.settings).start)

    def task(self, config, index, dtype=jnp.float32) -> CorridorTask:
        """World.task: task ``index``'s params (``index`` may be traced: each array indexed by it)."""
        return jax.tree.map(lambda column: jnp.asarray(column)[index], task_table(self.settings))

    def childhood_task(self, config, dtype=jnp.float32) -> CorridorTask:
        """World.childhood_task: a task's structure with no goal (never reached)."""
        return CorridorTask(jnp.int32(0), jnp.int32(1), jnp.int32(-1))

    def shortest(self) -> np.ndarray:
        """(tasks,) each task's fewest steps: the cells to its goal, and a turn when it starts facing away."""
        t = task_table(self.settings)
        return np.abs(t.goal - t.start) + ((t.goal - t.start) * t.facing < 0)

    def max_reaches(self, config, dtype=jnp.float32) -> jnp.ndarray:
        """World.max_reaches: the whole shortest solutions in ``config.task_steps`` steps (a reach restarts)."""
        return jnp.asarray(config.task_steps // self.shortest(), dtype)

    def make_env(self, config, has_target: bool = True, respawn: bool = False) -> CorridorEnv:
        """World.make_env: a task's trials (with a target), or childhood's open corridor (respawns or not)."""
        return CorridorEnv(self.settings, self.settings.trial_timeout or config.trial_timeout, has_target, respawn)


#: What a config's ``world_settings`` are read into (``--world-set`` parses them by its fields).
SETTINGS = CorridorSettings


def make_world(settings: dict) -> Corridor:
    """The world of a config's ``world_settings`` (a TypeError or ValueError names a wrong one)."""
    return Corridor(CorridorSettings(**settings))
