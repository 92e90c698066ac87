"""XLand-MiniGrid as a second world (issue #56): coloured corridors, a door and a key; six tasks of composed skills.

The arena's idea on a grid (docs/WORLDS.md): three corridors of coloured floor meet at a hub, each bent
once (red south then west, green west then north, blue east then south), a closed green door on the green
one and a yellow key ending the blue one. A task starts at the end of one corridor facing the hub and ends
at the end of another (red, green: on that cell; blue: holding the key), so each is solved by following one
colour, then another, opening the door or picking up the key on the way, and no one colour follower, constant
action or short cycle of actions solves any. The room, its tiles, the goals (xminigrid's
``AgentOnPositionGoal`` and ``AgentHoldGoal``) and the tasks are all built here, from :class:`XLandSettings`;
nothing is downloaded. No xminigrid rule is used: the tiles never transform.

    world = XLand()                                    # XLandSettings(): an 11 x 11 room, a 3 x 3 view
    env = world.make_env(config)                       # a task's trials (config.trial_timeout steps each)
    state = env.reset(key, world.task(config, 0))      # the agent at task 1's start
    x = env.observe(state)                             # 55 numbers
    state, events = env.transition(state, action, params)   # action: an index into XLandSettings.actions

xminigrid is an optional extra (``pip install -e '.[worlds]'``), imported when this module is.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
from typing import ClassVar, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

try:
    from xminigrid.core.actions import take_action
    from xminigrid.core.constants import DIRECTIONS, TILES_REGISTRY, Colors, Tiles
    from xminigrid.core.goals import AgentHoldGoal, AgentOnPositionGoal, EmptyGoal, check_goal
    from xminigrid.core.observation import transparent_field_of_view
    from xminigrid.types import AgentState
except ImportError as error:  # the core package runs without the extra
    raise ImportError("imrl_jax.world.xland needs xminigrid: pip install -e '.[worlds]'") from error

from imrl_jax.config import MAX_STEPS
from imrl_jax.world.base import DISCRETE, Actions, Events

#: xminigrid's action ids (its ``take_action``): put down (4) is left out, no task needs it.
FORWARD, TURN_RIGHT, TURN_LEFT, PICK_UP, TOGGLE = 0, 1, 2, 3, 5
#: xminigrid's directions: 0 up (north), 1 right, 2 down, 3 left.
UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3


MAX_ARM_LENGTH = 20  # a room of 43 x 43 cells
MAX_VIEW_SIZE = 9


@dataclasses.dataclass(frozen=True)
class XLandSettings:
    """The grid world's own settings: the room, the view and its encoding, the actions, the tasks and the trials."""

    # the corridors' reach (at least 3): arm_length - 1 cells out of the hub, then 2 past the bend (blue: 1 and the
    # key); the room is 2 arm_length + 3 cells wide
    arm_length: int = 4
    view_size: int = 3  # the view: view_size rows ahead (the agent's own row included) x view_size columns
    colours: tuple[int, ...] = (Colors.RED, Colors.GREEN, Colors.BLUE)  # each a one-hot input per cell
    # each group of tiles one input per cell: blocked (a wall, or outside the room), a closed door, a key
    tiles: tuple[tuple[int, ...], ...] = ((Tiles.WALL, Tiles.EMPTY), (Tiles.DOOR_CLOSED, Tiles.DOOR_LOCKED),
                                          (Tiles.KEY,))
    pocket: bool = True  # one more input: the agent holds something
    actions: tuple[int, ...] = (FORWARD, TURN_RIGHT, TURN_LEFT, PICK_UP, TOGGLE)  # xminigrid ids, by action index
    task_set: str = "xland"  # XLAND_TASK_SETS' name
    trial_timeout: int = 0  # steps of a trial; 0: the config's trial_timeout (the arena's 200)
    stuck_steps: int = 20  # with respawns: steps in a row without moving before a random start

    def __post_init__(self):
        # Upper bounds too: a room or a view of absurd size would be built (and fill the memory) before a life.
        if not 3 <= self.arm_length <= MAX_ARM_LENGTH:
            raise ValueError(f"XLandSettings.arm_length must be from 3 (the door and a start lie past it) to "
                             f"{MAX_ARM_LENGTH}, got {self.arm_length}")
        if not 3 <= self.view_size <= MAX_VIEW_SIZE or self.view_size % 2 == 0:
            raise ValueError(f"XLandSettings.view_size must be odd, from 3 to {MAX_VIEW_SIZE}, got {self.view_size}")
        if not 0 <= self.trial_timeout <= MAX_STEPS or not 1 <= self.stuck_steps <= MAX_STEPS:
            raise ValueError(f"XLandSettings: trial_timeout must be from 0 and stuck_steps from 1, both to "
                             f"{MAX_STEPS:,}, got {self.trial_timeout} and {self.stuck_steps}")
        if self.task_set not in XLAND_TASK_SETS:  # defined below: read when settings are made, after this module
            raise ValueError(f"task_set: {self.task_set!r} is not one of {', '.join(XLAND_TASK_SETS)}")

    @property
    def size(self) -> int:
        """The room's side in cells, walls included."""
        return 2 * self.arm_length + 3

    @property
    def hub(self) -> int:
        """The hub's row and column (the room's centre)."""
        return self.arm_length + 1


class XTask(NamedTuple):
    """A task: where trials start, the goal (on a cell, or holding a tile), and the skills that solve it in order."""

    start: tuple[int, int]  # (row, column)
    direction: int  # UP, RIGHT, DOWN, LEFT
    goal: tuple  # ("on", (row, column)) or ("hold", (tile, colour))
    skills: tuple[str, ...]  # "red", "green", "blue" (follow that path), "door" (open it), "key" (pick it up)


#: The key ending the blue path: the one yellow tile of the room.
KEY_TILE = (Tiles.KEY, Colors.YELLOW)


def _arms(s: XLandSettings) -> dict:
    """Each arm's end, the direction facing back along it to the hub, and its goal (on the end, or holding the key)."""
    h, n = s.hub, s.arm_length
    return {
        "red": ((h + n - 1, h - 2), RIGHT, ("on", (h + n - 1, h - 2))),
        "green": ((h - 2, h - n + 1), DOWN, ("on", (h - 2, h - n + 1))),
        "blue": ((h + 1, h + n - 1), UP, ("hold", KEY_TILE)),
    }


def _route(first: str, second: str) -> tuple[str, ...]:
    """Following ``first`` then ``second``, opening the door on the green path and picking up the key ending the blue."""
    skills = [first, second]
    if "green" in skills:
        skills.insert(skills.index("green") + 1, "door")
    if second == "blue":
        skills.append("key")
    return tuple(skills)


def paper_tasks(s: XLandSettings) -> tuple[XTask, ...]:
    """Six tasks as section 2's: from each arm's end (facing the hub) to each other arm's goal, in pairs by start."""
    arms = _arms(s)
    return tuple(XTask(arms[a][0], arms[a][1], arms[b][2], _route(a, b))
                 for a in ("red", "green", "blue") for b in ("red", "green", "blue") if a != b)


def novel_tasks(s: XLandSettings) -> tuple[XTask, ...]:
    """Six tasks never met in evolution: from inside each arm facing away from the hub (out, turn round, back, on)."""
    h, n, arms = s.hub, s.arm_length, _arms(s)
    starts = {"red": ((h + 2, h), DOWN), "green": ((h - 1, h - n + 1), UP), "blue": ((h, h + 2), RIGHT)}
    return tuple(XTask(starts[a][0], starts[a][1], arms[b][2], _route(a, b))
                 for a in ("red", "green", "blue") for b in ("red", "green", "blue") if a != b)


#: The task sets by name, as imrl_jax.world.tasks.TASK_SETS for the arena.
XLAND_TASK_SETS = {"xland": paper_tasks, "xland-novel": novel_tasks}


def tasks(s: XLandSettings) -> tuple[XTask, ...]:
    """The settings' task set (a name XLandSettings checked)."""
    return XLAND_TASK_SETS[s.task_set](s)


@functools.lru_cache(maxsize=16)
def room(s: XLandSettings) -> np.ndarray:
    """The room (size, size, 2) of (tile, colour): three corridors meeting at a hub, each of one colour and bent once
    (red south then west, green west then north, blue east then south), a closed green door on the green one, the
    key ending the blue one; walls elsewhere."""
    h, n = s.hub, s.arm_length
    grid = np.zeros((s.size, s.size, 2), np.uint8)
    grid[...] = (Tiles.WALL, Colors.GREY)
    grid[h, h] = (Tiles.FLOOR, Colors.BLACK)
    for d in range(1, n):
        grid[h + d, h] = (Tiles.FLOOR, Colors.RED)
        grid[h, h - d] = (Tiles.FLOOR, Colors.GREEN)
        grid[h, h + d] = (Tiles.FLOOR, Colors.BLUE)
    for d in (1, 2):
        grid[h + n - 1, h - d] = (Tiles.FLOOR, Colors.RED)
        grid[h - d, h - n + 1] = (Tiles.FLOOR, Colors.GREEN)
    grid[h + 1, h + n - 1] = (Tiles.FLOOR, Colors.BLUE)
    grid[h, h - 2] = (Tiles.DOOR_CLOSED, Colors.GREEN)
    grid[h + 2, h + n - 1] = KEY_TILE
    return grid


@functools.lru_cache(maxsize=16)
def free_cells(s: XLandSettings) -> np.ndarray:
    """(cells, 2) the floor's cells (coloured or not): where a random start may put the agent."""
    return np.argwhere(room(s)[:, :, 0] == Tiles.FLOOR).astype(np.int32)


def _goal_encoding(goal: tuple) -> np.ndarray:
    """xminigrid's encoding of ``("on", cell)`` or ``("hold", tile)`` (a constant, even while tracing)."""
    kind, what = goal
    with jax.ensure_compile_time_eval():
        if kind == "on":
            return np.asarray(AgentOnPositionGoal(position=jnp.asarray(what, jnp.uint8)).encode())
        if kind == "hold":
            return np.asarray(AgentHoldGoal(tile=jnp.asarray(what, jnp.uint8)).encode())
        return np.asarray(EmptyGoal().encode())


class XLandTask(NamedTuple):
    """A task's params (or childhood's: no goal): the room at a trial's start, the agent's start, the goal."""

    grid: jnp.ndarray  # (size, size, 2) uint8
    position: jnp.ndarray  # (2,) int32
    direction: jnp.ndarray  # () int32
    goal: jnp.ndarray  # xminigrid's goal encoding (5,) uint8


@functools.lru_cache(maxsize=16)
def _task_table(s: XLandSettings) -> XLandTask:
    ts = tasks(s)
    grid = np.broadcast_to(room(s), (len(ts),) + room(s).shape)
    return XLandTask(grid, np.asarray([t.start for t in ts], np.int32), np.asarray([t.direction for t in ts], np.int32),
                     np.stack([_goal_encoding(t.goal) for t in ts]))


def shortest_solution(s: XLandSettings, task: XTask) -> list[int]:
    """The fewest action indices that reach ``task``'s goal from its start (breadth-first over position, direction,
    the door's state and the key), as the arena's theoretical maximum takes the straight line at full speed."""
    grid = room(s)
    start = (tuple(task.start), task.direction, False, False)  # position, direction, door open, key held
    moves = [tuple(int(v) for v in d) for d in np.asarray(DIRECTIONS)]
    parents = {start: None}
    queue = collections.deque([start])
    while queue:
        state = queue.popleft()
        (r, c), d, door_open, held = state
        ahead = (r + moves[d][0], c + moves[d][1])
        tile = grid[ahead][0]
        for index, action in enumerate(s.actions):
            pos, new_d, new_open, new_held = (r, c), d, door_open, held
            if action == FORWARD and (tile == Tiles.FLOOR or (tile == Tiles.DOOR_CLOSED and door_open)):
                pos = ahead
            elif action == TURN_RIGHT:
                new_d = (d + 1) % 4
            elif action == TURN_LEFT:
                new_d = (d - 1) % 4
            elif action == TOGGLE and tile == Tiles.DOOR_CLOSED:
                new_open = not door_open
            elif action == PICK_UP and tile == Tiles.KEY and not held:
                new_held = True
            kind, what = task.goal
            done = pos == tuple(what) if kind == "on" else (action == PICK_UP and new_held)
            new = (pos, new_d, new_open, new_held)
            if done or new not in parents:
                parents[new] = (state, index)
                if done:
                    path, node = [], new
                    while parents[node] is not None:
                        node, taken = parents[node]
                        path.append(taken)
                    return path[::-1]
                queue.append(new)
    raise ValueError(f"no solution to {task}")


@functools.lru_cache(maxsize=16)
def _shortest(s: XLandSettings) -> np.ndarray:
    # Searched once per settings: every life and report that scores a task divides by it.
    return np.asarray([len(shortest_solution(s, t)) for t in tasks(s)])


class XLandState(NamedTuple):
    """The room and the agent in it."""

    grid: jnp.ndarray  # (size, size, 2) uint8: tiles change as doors open and keys are picked up
    position: jnp.ndarray  # (2,) int32
    direction: jnp.ndarray  # () int32
    pocket: jnp.ndarray  # (2,) uint8: the tile held (EMPTY, EMPTY: nothing)
    trial_step: jnp.ndarray  # steps since the trial started
    still: jnp.ndarray  # steps in a row without moving (with respawns)


def _agent(state: XLandState) -> AgentState:
    # In jax's default integer type, as xminigrid's literals: 64-bit where jax runs with 64-bit numbers (a float64
    # life), else int32 as the state's.
    return AgentState(position=jnp.asarray(state.position, int), direction=jnp.asarray(state.direction, int),
                      pocket=state.pocket)


@dataclasses.dataclass(frozen=True)
class XLandEnv:
    """The room with a task's goal and trials, or open (childhood, never reached); respawns or not."""

    settings: XLandSettings
    trial_timeout: int
    has_target: bool = True
    respawn: bool = False

    def at(self, grid, position, direction) -> XLandState:
        """The agent at ``position`` facing ``direction`` in ``grid``, holding nothing, a trial just started."""
        empty = jnp.asarray(TILES_REGISTRY[Tiles.EMPTY, Colors.EMPTY], jnp.uint8)
        return XLandState(jnp.asarray(grid, jnp.uint8), jnp.asarray(position, jnp.int32),
                          jnp.asarray(direction, jnp.int32), empty, jnp.int32(0), jnp.int32(0))

    def spawn(self, uniforms: jnp.ndarray) -> XLandState:
        """A fresh room with the agent on a random floor cell facing a random way (two uniform numbers in [0, 1))."""
        cells = jnp.asarray(free_cells(self.settings))
        cell = jnp.minimum((uniforms[0] * len(cells)).astype(jnp.int32), len(cells) - 1)
        direction = jnp.minimum((uniforms[1] * 4).astype(jnp.int32), 3)
        return self.at(room(self.settings), cells[cell], direction)

    def reset(self, key: jax.Array, params: XLandTask, dtype=jnp.float32) -> XLandState:
        """The agent at the task's start; without a target on a random floor cell drawn from ``key``."""
        if self.has_target:
            return self.at(params.grid, params.position, params.direction)
        return self.spawn(jax.random.uniform(key, (2,)))

    def observe(self, state: XLandState) -> jnp.ndarray:
        """The view ahead (:func:`encode`)."""
        return encode(self.settings, state)

    def transition(self, state: XLandState, action: jnp.ndarray, params: XLandTask, spawn=None):
        """xminigrid's action (``settings.actions[action]``); then, with respawns, a random start after
        ``stuck_steps`` steps without moving; with a target, the goal (reward 1) or the timeout restarts the trial."""
        act = jnp.asarray(self.settings.actions, jnp.int32)[action]
        grid, agent, changed = take_action(state.grid, _agent(state), act)
        moved = jnp.any(agent.position != state.position)
        new = XLandState(grid, agent.position.astype(jnp.int32), agent.direction.astype(jnp.int32), agent.pocket,
                         state.trial_step + 1, jnp.where(moved, 0, state.still + 1))
        respawned = reached = timeout = jnp.bool_(False)
        if self.respawn:
            respawned = new.still >= self.settings.stuck_steps
            new = jax.tree.map(lambda fresh, now: jnp.where(respawned, fresh, now), self.spawn(spawn), new)
        if self.has_target:
            reached = check_goal(params.goal, grid, agent, act, changed)
            timeout = ~reached & (new.trial_step >= self.trial_timeout)
            start = self.at(params.grid, params.position, params.direction)._replace(still=new.still)
            new = jax.tree.map(lambda s, now: jnp.where(reached | timeout, s, now), start, new)
        return new, Events(reached, timeout, respawned)


def encode(s: XLandSettings, state: XLandState) -> jnp.ndarray:
    """(inputs,) float32: for each cell of the view (far row first, left to right), its colour one-hot over
    ``s.colours`` then one input per group of ``s.tiles``; then whether the agent holds something."""
    view = transparent_field_of_view(state.grid, _agent(state), s.view_size, s.view_size).astype(jnp.int32)
    colours = view[:, :, 1:2] == jnp.asarray(s.colours, jnp.int32)
    width = max(len(group) for group in s.tiles)
    groups = jnp.asarray([g + (g[0],) * (width - len(g)) for g in s.tiles], jnp.int32)  # padded with its own first
    tiles = jnp.any(view[:, :, 0, None, None] == groups, axis=-1)
    cells = jnp.concatenate([colours, tiles], axis=-1).reshape(-1)
    held = (state.pocket[:1] != Tiles.EMPTY) if s.pocket else jnp.zeros((0,), bool)
    return jnp.concatenate([cells, held]).astype(jnp.float32)


@dataclasses.dataclass(frozen=True)
class XLand:
    """XLand-MiniGrid's room as a world (imrl_jax.world.base.World): paths, a door and a key; discrete actions."""

    settings: XLandSettings = XLandSettings()
    name: ClassVar[str] = "xland"
    #: A respawn's random start: a floor cell and a direction.
    num_spawn_draws: ClassVar[int] = 2

    def num_inputs(self, config=None) -> int:
        """View cells x (colours + tile groups), and the pocket: 3 x 3 x (3 + 3) + 1 = 55 by default."""
        s = self.settings
        return s.view_size ** 2 * (len(s.colours) + len(s.tiles)) + int(s.pocket)

    def actions(self, config=None) -> Actions:
        """One of ``settings.actions``: forward, turn right, turn left, pick up, toggle by default."""
        return Actions(DISCRETE, len(self.settings.actions))

    def num_tasks(self, config=None) -> int:
        """The task set's tasks (six)."""
        return len(tasks(self.settings))

    def task(self, config, index, dtype=jnp.float32) -> XLandTask:
        """Task ``index``'s params (``index`` may be traced)."""
        return jax.tree.map(lambda table: jnp.asarray(table)[index], _task_table(self.settings))

    def childhood_task(self, config, dtype=jnp.float32) -> XLandTask:
        """The room with no goal (xminigrid's empty goal, never checked)."""
        return XLandTask(jnp.asarray(room(self.settings)), jnp.zeros((2,), jnp.int32), jnp.int32(0),
                         jnp.asarray(_goal_encoding(("none", None))))

    def shortest(self) -> np.ndarray:
        """(tasks,) each task's shortest solution in steps."""
        return _shortest(self.settings)

    def max_reaches(self, config, dtype=jnp.float32) -> jnp.ndarray:
        """(tasks,) the whole shortest solutions that fit in ``config.task_steps`` steps (a reach's step restarts)."""
        return jnp.asarray(config.task_steps // self.shortest(), dtype)

    def make_env(self, config, has_target: bool = True, respawn: bool = False) -> XLandEnv:
        """A task's trials (with a target), or the open room of childhood (respawns or not)."""
        return XLandEnv(self.settings, self.settings.trial_timeout or config.trial_timeout, has_target, respawn)


#: The dataclass of a config's ``world_settings`` in this world (``--world-set`` parses them by its fields).
SETTINGS = XLandSettings


def make_world(settings: dict) -> XLand:
    """The world of a config's ``world_settings`` (their names checked by ``worlds.make`` against
    :data:`SETTINGS`; raises ValueError naming a setting whose value is wrong)."""
    return XLand(XLandSettings(**settings))
