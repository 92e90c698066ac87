"""Hand-written controllers of the XLand world (imrl_jax.world.xland): composed skills solve every task, no fixed
behaviour does (docs/WORLDS.md, "XLand-MiniGrid: the second world").

Not part of the model; nothing here learns. As :mod:`imrl_jax.analysis.controllers` shows the arena's tasks
solvable by composing colour followers, this shows the grid's: every controller reads only the observation
a perceptron reads (:func:`imrl_jax.world.xland.encode`, the default settings' encoding) and acts through
the environment's own transition, trials ending as in adulthood.

* **skills**: ``follow(c)`` keeps to the path of colour c (ahead if it is c, else turn towards c on the
  left or right, else on towards c seen further ahead, else turn left: at a path's end it turns round);
  ``door`` toggles a closed door ahead; ``key`` picks up a key ahead;
* the **composition** of a task follows its route's first colour, then its second from when that colour
  comes into view with the hub ahead, opening any door ahead and, when the route ends at the key, picking it up;
* the **fixed behaviours**, none of which composes: each constant action, each cycle of 2 or 3 actions,
  uniformly random actions, and each single colour follower with the door and key reflexes.

Scores are reaches / the most reaches (whole shortest solutions, :func:`imrl_jax.world.xland.shortest_solution`).
"""

from __future__ import annotations

import functools
import itertools
import time

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.config import Config
from imrl_jax.world.xland import FORWARD, PICK_UP, TOGGLE, TURN_LEFT, TURN_RIGHT, XLand, XLandSettings, tasks

COLOURS = ("red", "green", "blue")
#: The default encoding's tile groups, by index in a cell's inputs after the colours: blocked, door, key.
BLOCKED, DOOR, KEY = 0, 1, 2


def _index(s: XLandSettings, action: int) -> int:
    return s.actions.index(action)


def _cells(s: XLandSettings, x: jnp.ndarray) -> jnp.ndarray:
    """(view, view, colours + tile groups) booleans of an observation."""
    per_cell = len(s.colours) + len(s.tiles)
    return x[:s.view_size ** 2 * per_cell].reshape(s.view_size, s.view_size, per_cell) > 0.5


def follow(s: XLandSettings, x: jnp.ndarray, colour) -> jnp.ndarray:
    """The action index of ``follow(colour)`` (colour an index into ``s.colours``) on observation ``x``."""
    cells, v, mid, nc = _cells(s, x), s.view_size, s.view_size // 2, len(s.colours)
    ahead, left, right = cells[v - 2, mid], cells[v - 1, mid - 1], cells[v - 1, mid + 1]
    free = ~(ahead[nc + BLOCKED] | ahead[nc + DOOR] | ahead[nc + KEY])
    further = cells[:v - 1, :, colour].any()
    plain = ~ahead[:nc].any()  # towards c over uncoloured floor only (the hub), never along another colour's path
    return jnp.select(
        [ahead[colour] & free, left[colour], right[colour], further & free & plain],
        [_index(s, FORWARD), _index(s, TURN_LEFT), _index(s, TURN_RIGHT), _index(s, FORWARD)],
        _index(s, TURN_LEFT))


def compose(s: XLandSettings, x: jnp.ndarray, route, stage, takes_key) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The composition's action index and stage: (route[0], route[1]) followed in turn, doors opened, the key picked
    up at the route's end if ``takes_key``."""
    cells, v, mid, nc = _cells(s, x), s.view_size, s.view_size // 2, len(s.colours)
    ahead = cells[v - 2, mid]
    at_hub = ~ahead[:nc].any() & ~ahead[nc:].any()  # uncoloured floor ahead: the hub, where the paths meet
    stage = jnp.where(at_hub & cells[:, :, route[1]].any(), 1, stage)
    action = jnp.where(ahead[nc + DOOR], _index(s, TOGGLE),
                       jnp.where(ahead[nc + KEY] & takes_key & (stage == 1), _index(s, PICK_UP),
                                 follow(s, x, route[stage])))
    return action, stage


def _drive(world: XLand, config: Config, num_steps: int, task_index, policy, params, key=None):
    """Reaches of ``policy(x, t, memory, params, key) -> (action, memory)`` in ``num_steps`` steps of a task."""
    env, task = world.make_env(config), world.task(config, task_index)
    key = jax.random.key(0) if key is None else key

    def one_step(carry, t):
        state, memory, reaches = carry
        action, memory = policy(env.observe(state), t, memory, params, jax.random.fold_in(key, t))
        state, events = env.transition(state, action, task)
        memory = jnp.where(events.reached | events.timeout, 0, memory)
        return (state, memory, reaches + events.reached), None

    start = (env.reset(key, task), jnp.int32(0), jnp.int32(0))
    (_, _, reaches), _ = jax.lax.scan(one_step, start, jnp.arange(num_steps))
    return reaches


def _routes(s: XLandSettings) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(tasks, 2) each task's two colours (indices into COLOURS), and (tasks,) whether it ends holding the key."""
    ts = tasks(s)
    routes = [[COLOURS.index(k) for k in t.skills if k in COLOURS] for t in ts]
    return jnp.asarray(routes, jnp.int32), jnp.asarray(["key" in t.skills for t in ts])


def most_reaches(world: XLand, num_steps: int) -> np.ndarray:
    """(tasks,) whole shortest solutions in ``num_steps`` steps: the score's denominator."""
    return num_steps // world.shortest()


@functools.partial(jax.jit, static_argnums=(0, 1, 2))
def composition_reaches(world: XLand, config: Config, num_steps: int) -> jnp.ndarray:
    """(tasks,) reaches of each task's composition."""
    s = world.settings
    routes, keys = _routes(s)

    def policy(x, t, stage, params, key):
        return compose(s, x, params[0], stage, params[1])

    return jax.vmap(lambda i: _drive(world, config, num_steps, i, policy, (routes[i], keys[i])))(
        jnp.arange(world.num_tasks()))


def cycles(world: XLand, lengths=(1, 2, 3)) -> np.ndarray:
    """(cycles, 3) every cycle of actions of the given lengths, padded by repeating it (period 1, 2 or 3)."""
    num = len(world.settings.actions)
    rows = [(seq * 3)[:3] for n in lengths for seq in itertools.product(range(num), repeat=n)]
    return np.asarray(rows, np.int32)


@functools.partial(jax.jit, static_argnums=(0, 1, 2))
def fixed_reaches(world: XLand, config: Config, num_steps: int, sequences, keys) -> dict:
    """Reaches of the fixed behaviours on every task: ``cycle`` (cycles, tasks) for the (cycles, 3) ``sequences``
    (a constant action is a cycle of period 1), ``random`` (seeds, tasks) with one key each, ``follower``
    (colours, tasks): one colour followed throughout, doors opened and keys picked up on the way."""
    s, task_indices = world.settings, jnp.arange(world.num_tasks())

    def cycle(x, t, memory, sequence, key):
        return sequence[t % 3], memory

    def random(x, t, memory, params, key):
        return jax.random.randint(key, (), 0, len(s.actions)), memory

    def follower(x, t, stage, colour, key):
        return compose(s, x, jnp.stack([colour, colour]), stage, jnp.bool_(True))

    def grid(policy, params, lane_keys=None):
        def one(p, k):
            return jax.vmap(lambda i: _drive(world, config, num_steps, i, policy, p, k))(task_indices)
        lane_keys = jax.random.split(jax.random.key(0), len(params)) if lane_keys is None else lane_keys
        return jax.vmap(one)(params, lane_keys)

    return {"cycle": grid(cycle, jnp.asarray(sequences)),
            "random": grid(random, jnp.zeros(len(keys)), keys),
            "follower": grid(follower, jnp.arange(len(COLOURS)))}


def scores(world: XLand, config: Config, num_steps: int = 2_000, num_seeds: int = 4) -> dict:
    """Per task: the composition's score and the best score of each family of fixed behaviours (and which cycle)."""
    best = most_reaches(world, num_steps)
    sequences = cycles(world)
    fixed = fixed_reaches(world, config, num_steps, sequences, jax.random.split(jax.random.key(1), num_seeds))
    result = {"most": best, "composition": np.asarray(composition_reaches(world, config, num_steps)) / best}
    for name, reaches in fixed.items():
        result[name] = np.asarray(reaches).max(axis=0) / best
    result["best_cycle"] = [sequences[i].tolist() for i in np.asarray(fixed["cycle"]).argmax(axis=0)]
    return result


def table(world: XLand, config: Config, num_steps: int = 2_000) -> str:
    """Markdown: per task, its skills, the most reaches, the composition's score and the best fixed behaviours'."""
    r = scores(world, config, num_steps)
    lines = ["| task | skills | most reaches | composition | best constant or cycle | random | best single follower |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for i, t in enumerate(tasks(world.settings)):
        lines.append(f"| {i + 1} | {', '.join(t.skills)} | {r['most'][i]} | {r['composition'][i]:.2f} | "
                     f"{r['cycle'][i]:.2f} | {r['random'][i]:.2f} | {r['follower'][i]:.2f} |")
    return "\n".join(lines)


def speed(world: XLand, config: Config, num_lanes: int = 1_024, num_steps: int = 1_000) -> float:
    """Lane-steps per second of a vmapped random-action step (observe, act, transition) on task 1, compilation
    excluded."""
    def run(key):
        def lane(k):
            def policy(x, t, memory, params, step_key):
                action = jax.random.randint(step_key, (), 0, len(world.settings.actions))
                return jnp.where(x.sum() < 0, 0, action), memory  # reads the view: it is computed, as an agent's
            return _drive(world, config, num_steps, 0, policy, None, k)
        return jax.vmap(lane)(jax.random.split(key, num_lanes))

    run = jax.jit(run)
    run(jax.random.key(0)).block_until_ready()
    begin = time.perf_counter()
    run(jax.random.key(1)).block_until_ready()
    return num_lanes * num_steps / (time.perf_counter() - begin)
