"""A hand-written composition of three colour-following controllers (MODEL.md task table).

This is not part of the model and nothing in it learns or evolves. It exists to show that
the six tasks of MODEL.md are solvable with the retina and the kinematics that MODEL.md
fixes (a 6 x 2 RGB retina 17-21 cm ahead, turns of at most 30 deg and moves of at most
2 cm per step), and how well: MODEL.md reports 0.88-0.90 per task for a composition of
perceptron colour-followers, the practical ceiling against which learned results compare.

It is plain code, not perceptrons:

* one **follower** per colour steers towards the centroid of the retina points that see
  its colour (pure pursuit: turn by the angle of that centroid as seen from the robot's
  centre, at most 30 deg) and always drives at full speed; when its colour is out of
  sight it keeps the last turn it made;
* a **route** per task is the sequence of edge colours from start to target. It is
  derived from the task table: walk the zigzag from the start vertex along the start
  heading, turning alternately left and right by 60 deg at every vertex, until the
  target is reached (:func:`zigzag_route`). Edge colour follows edge direction, so after
  a left turn red -> green -> blue -> red and after a right turn red -> blue -> green -> red;
* the **composition** follows the route's current colour and moves on to the next one
  when that colour appears in the retina (which happens only at the next junction, where
  it is the branch to take), at least ``MIN_DWELL`` steps after the last switch (so the
  end of the edge just left, still in view, does not count as the next junction).

Everything is pure JAX (no Python control flow on traced values), so a run is one
``lax.scan`` and runs for several tasks and routes are one ``vmap``. Trials end exactly as
in the adult phase (:func:`imrl_jax.agent.lifetime.step`): on coming within
``config.target_radius`` of the target (a reach) or ``config.trial_timeout`` steps after
the trial's start without reaching it, the robot is put back at the task's start pose
and the route starts again.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.config import Config
from imrl_jax.world.env import EnvState, make_env, task_spec
from imrl_jax.world.tasks import MAX_ROUTE, zigzag_route
from imrl_jax.agent.lifetime import make_evaluate

#: Steps after a switch during which the next colour does not trigger another switch
#: (20 cm: half an edge; consecutive junctions of a route are about 40 cm apart).
MIN_DWELL = 10
#: Forward distance (cm) at which a follower aims: the middle of the retina's two rows.
AIM_DISTANCE = 19.0
def route_table(config: Config) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Routes of all tasks as arrays: colours (tasks, MAX_ROUTE) padded with -1, lengths."""
    routes = [zigzag_route(config, t)[0] for t in config.tasks]
    colours = jnp.asarray([r + (-1,) * (MAX_ROUTE - len(r)) for r in routes], jnp.int32)
    return colours, jnp.asarray([len(r) for r in routes], jnp.int32)


def follow(config: Config, x: jnp.ndarray, colour, last_turn) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The follower of ``colour``: action (a0, a1) for retina input ``x``, and its turn (rad).

    Turns towards the centroid of the points seeing the colour (at most ``max_turn``), or
    by ``last_turn`` when the colour is out of sight; always full speed.
    """
    rows, lateral = len(config.retina_forward), len(config.retina_lateral)
    seen = x.reshape(rows, lateral, 3)[:, :, colour]
    offsets = jnp.asarray(config.retina_lateral, x.dtype)[None, :]
    count = seen.sum()
    centre = (seen * offsets).sum() / jnp.maximum(count, 1.0)
    max_turn = math.radians(config.max_turn_deg)
    turn = jnp.clip(jnp.arctan2(centre, AIM_DISTANCE), -max_turn, max_turn)
    turn = jnp.where(count > 0, turn, last_turn)
    action = jnp.stack([0.5 + turn / (2.0 * max_turn), jnp.ones((), x.dtype)])
    return action, turn


class ControllerState(NamedTuple):
    """Scan carry of a controller run."""

    robot: EnvState  # the robot in the task's environment
    stage: jnp.ndarray  # index into the route of the colour being followed
    dwell: jnp.ndarray  # steps since the last switch of stage
    last_turn: jnp.ndarray  # the follower's last turn, kept while its colour is out of sight
    reaches: jnp.ndarray


def _run(config: Config, num_steps: int, task_index, route_index, record: bool = False):
    """Reaches of the route of task ``route_index`` driven on task ``task_index`` (and, if ``record``, each step)."""
    colours, lengths = route_table(config)
    return _drive(config, num_steps, task_index, colours[route_index], lengths[route_index], record)


def _drive(config: Config, num_steps: int, task_index, route, length, record: bool = False):
    """Reaches of the colour route ``route`` (MAX_ROUTE, padded; ``length`` used) driven on task ``task_index``."""
    task, arena = task_spec(config, task_index), make_env(config)
    dtype = task.start.pos.dtype

    def one_step(state: ControllerState, _):
        x = arena.observe(state.robot)
        # Switch to the route's next colour when it comes into view at the next junction.
        has_next = state.stage + 1 < length
        next_colour = route[jnp.minimum(state.stage + 1, MAX_ROUTE - 1)]
        next_seen = x.reshape(-1, 3)[:, next_colour].sum() > 0
        switch = has_next & next_seen & (state.dwell >= MIN_DWELL)
        stage = state.stage + switch
        dwell = jnp.where(switch, 0, state.dwell + 1)
        action, turn = follow(config, x, route[stage], state.last_turn)
        # Trials end as in the adult phase: a reach or the timeout.
        robot, events = arena.transition(state.robot, action, task)
        reached, timeout = events.reached, events.timeout
        reset = reached | timeout
        new = ControllerState(
            robot=robot,
            stage=jnp.where(reset, 0, stage),
            dwell=jnp.where(reset, 0, dwell),
            last_turn=jnp.where(reset, 0.0, turn),
            reaches=state.reaches + reached,
        )
        if not record:
            return new, None
        colour = route[stage]  # the follower in control: 0 red, 1 green, 2 blue
        # The Trajectory's fields: no respawns here (the composition drives adult tasks only).
        return new, (state.robot.pose.pos, state.robot.pose.heading, robot.pose.pos, robot.pose.heading, colour,
                     reached, timeout, jnp.zeros_like(reached))

    start = ControllerState(arena.at(task.start), jnp.int32(0), jnp.int32(0), jnp.zeros((), dtype), jnp.int32(0))
    final, steps = jax.lax.scan(one_step, start, None, length=num_steps)
    return (final.reaches, steps) if record else final.reaches


def run_controller(config: Config, task_index, num_steps: int, route_index=None) -> jnp.ndarray:
    """Reaches of the composition on task ``task_index`` in ``num_steps`` steps.

    ``route_index`` (default: the task's own) picks whose route the composition follows,
    e.g. task 1's route on task 2 to check that one fixed controller cannot solve both
    tasks of a pair. Jit- and vmap-friendly in both indices; ``num_steps`` is static.
    """
    route_index = task_index if route_index is None else route_index
    return _run(config, num_steps, task_index, route_index)


@functools.partial(jax.jit, static_argnums=(0, 1))
def run_many(config: Config, num_steps: int, task_indices, route_indices) -> jnp.ndarray:
    """Reaches of many (task, route) runs at once: one compilation, vmapped."""
    return jax.vmap(lambda t, r: _run(config, num_steps, t, r))(task_indices, route_indices)


@functools.partial(jax.jit, static_argnums=(0, 1))
def _recorded(config: Config, num_steps: int):
    tasks = jnp.arange(config.num_tasks)
    return jax.vmap(lambda t: _run(config, num_steps, t, t, record=True)[1])(tasks)


def trajectories(config: Config, num_steps: int) -> list:
    """The composition's first ``num_steps`` steps on each task as :class:`imrl_jax.analysis.behaviour.Trajectory`
    (``k``: the colour followed, 0 red, 1 green, 2 blue)."""
    import numpy as np

    from imrl_jax.analysis.behaviour import Trajectory

    steps = [np.asarray(x) for x in _recorded(config, num_steps)]
    return [Trajectory(*(x[i] for x in steps)) for i in range(config.num_tasks)]


def performance(config: Config, num_steps: int) -> jnp.ndarray:
    """(tasks,) reaches / (num_steps / steps per trip) of every task on its own route."""
    tasks = jnp.arange(config.num_tasks)
    reaches = run_many(config, num_steps, tasks, tasks)
    return reaches / (num_steps / jnp.asarray(config.steps_per_trip(), jnp.float32))


@functools.partial(jax.jit, static_argnums=(0, 1))
def follower_performance(config: Config, num_steps: int) -> jnp.ndarray:
    """(colours, tasks) performance of one fixed colour follower (red, green, blue) on every task: a controller that
    cannot compose, to compare with the composition (:func:`performance`)."""
    trips = num_steps / jnp.asarray(config.steps_per_trip(), jnp.float32)

    def one(colour, task):
        route = jnp.full((MAX_ROUTE,), colour, jnp.int32)
        return _drive(config, num_steps, task, route, jnp.int32(1))

    colours, tasks = jnp.meshgrid(jnp.arange(3), jnp.arange(config.num_tasks), indexing="ij")
    reaches = jax.vmap(jax.vmap(one))(colours, tasks)
    return reaches / trips


@functools.partial(jax.jit, static_argnums=(0, 2))
def constant_performance(config: Config, actions: jnp.ndarray, num_steps: int) -> jnp.ndarray:
    """(actions, tasks) performance of a robot that ignores its retina and repeats one action (turn, speed) from
    each task's start: a circle (a straight line at turn 0.5) through the start, begun again at every trial's end.
    The stereotyped circular path of the paper's EE-ES (section 4), at its simplest."""
    trips = num_steps / jnp.asarray(config.steps_per_trip(), jnp.float32)
    arena = make_env(config)

    def one(action, task_index):
        task = task_spec(config, task_index)

        def one_step(state: EnvState, _):
            state, events = arena.transition(state, action.astype(task.start.pos.dtype), task)
            return state, events.reached

        _, reached = jax.lax.scan(one_step, arena.at(task.start), None, length=num_steps)
        return reached.sum()

    tasks = jnp.arange(config.num_tasks)
    reaches = jax.vmap(lambda a: jax.vmap(lambda t: one(a, t))(tasks))(jnp.asarray(actions))
    return reaches / trips


def perceptron_followers(config: Config, turn_gain: float = 0.1, speed_bias: float = 6.0) -> jnp.ndarray:
    """Expert actor weights (K, 2, n+1) that follow colour k: perceptrons, as an evolved expert could be.

    Turn unit: weight ``turn_gain * l`` on the colour-k receptor at lateral offset l (cm,
    positive = left), so the robot turns towards its colour and goes straight when it sees
    none. Speed unit: bias ``speed_bias`` (sigmoid(6) = 0.998 of full speed). These are the
    "ideal perceptron colour-followers" of MODEL.md's learning-extension measurements; as an
    EE-LS genome (``.reshape(-1)``) they isolate how well the selector learns to compose them.
    """
    rows, lateral = len(config.retina_forward), len(config.retina_lateral)
    n = config.num_inputs + 1
    offsets = jnp.asarray(config.retina_lateral, jnp.float32)
    actors = []
    for k in range(config.num_experts):
        turn = jnp.zeros((rows, lateral, 3), jnp.float32).at[:, :, k % 3].set(turn_gain * offsets[None, :])
        speed = jnp.zeros((n,), jnp.float32).at[-1].set(speed_bias)
        actors.append(jnp.stack([jnp.append(turn.reshape(-1), 0.0), speed]))
    return jnp.stack(actors)


def composition_ceiling(key: jax.Array, config: Config, num_lives: int = 8, turn_gain: float = 0.1):
    """What composing ideal experts is worth: lives of EE-LS individuals whose experts are
    :func:`perceptron_followers` and whose selector learns as in adulthood under ``config``'s
    rules and task length. Returns the ``LifetimeResult`` of ``num_lives`` lives (fitness (lives,)).

    Evolution climbs towards this when it makes experts that follow one colour each; an
    evolved individual with unspecialised experts above it means composition does not pay
    under those rules (docs/CHILDHOOD.md).
    """
    config = config.replace(condition="EE-LS")
    genome = perceptron_followers(config, turn_gain).reshape(-1)
    genomes = jnp.broadcast_to(genome, (num_lives,) + genome.shape)
    return make_evaluate(config)(key, config.learning_params(), genomes)
