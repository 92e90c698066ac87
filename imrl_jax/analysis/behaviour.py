"""Behaviour of one individual (section 3 of the paper, MODEL.md claim 7): paths, retina views, what experts follow.

Everything here records per-step data of a single individual with
:func:`imrl_jax.agent.lifetime.simulate` and is meant for pictures and small analyses, not for
evolution (which keeps only reductions). A :class:`Trajectory` holds, for each step, the
pose at which the expert was chosen (what the retina saw), the pose after the step, the
expert in control and the events; :func:`colour_shares` turns it into "what each expert
follows": the share of its control steps on which the retina's central receptors see red,
green, blue or nothing.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.world.arena import Pose, floor_colour
from imrl_jax.config import Config, LearningParams
from imrl_jax.conditions import Phase
from imrl_jax.agent.lifetime import childhood_task, lifetime_keys, random_pose, run_phase, simulate, task_spec
from imrl_jax.agent.state import childhood_phase, for_phase, init_state
from imrl_jax.agent.networks import Agent, decode
from imrl_jax.world.retina import sample_points
from imrl_jax.world.env import at

#: Names of the columns of :func:`colour_shares`.
SEEN = ("red", "green", "blue", "nothing")
#: A phase in which nothing learns, there is no target and no noise (probes of experts).
PROBE = Phase(experts_learn=False, selector_learns=False, intrinsic=False, has_target=False, noisy=False)
#: Selector bias that makes one expert take control (sigmoid(-40) ~ 4e-18 for the others).
_FORCE = 40.0


class Trajectory(NamedTuple):
    """Per-step record of one individual (leading axis: steps)."""

    seen_pos: np.ndarray  # (T, 2) position the expert was chosen at (what the retina saw)
    seen_heading: np.ndarray  # (T,)
    pos: np.ndarray  # (T, 2) position after the step (after a reset: the start)
    heading: np.ndarray  # (T,)
    k: np.ndarray  # (T,) expert in control
    reached: np.ndarray  # (T,) the step reached the target
    timeout: np.ndarray  # (T,) the step ended a trial by the timeout
    respawned: np.ndarray  # (T,) the step put the robot at a random pose after a wall (childhood option)

    @property
    def breaks(self) -> np.ndarray:
        """(T,) True where the robot was put elsewhere after the step (the start, or a random pose)."""
        return self.reached | self.timeout | self.respawned

    def as_path(self) -> dict:
        """The dict :func:`imrl_jax.analysis.arena_figures.plot_life` draws (pos, k, breaks)."""
        return {"pos": self.pos, "k": self.k, "breaks": self.breaks}

    def window(self, start: int, stop: int) -> "Trajectory":
        """Steps start .. stop-1."""
        return Trajectory(*(x[start:stop] for x in self))


def _trajectory(start: Pose, record) -> Trajectory:
    """A Trajectory from a start pose and simulate's records (jnp in, numpy out; batched too)."""
    pos, heading = record.world.pose.pos, record.world.pose.heading
    seen_pos = jnp.concatenate([start.pos[..., None, :], pos[..., :-1, :]], -2)
    seen_heading = jnp.concatenate([start.heading[..., None], heading[..., :-1]], -1)
    return Trajectory(*(np.asarray(x) for x in (seen_pos, seen_heading, pos, heading, record.k, record.reached,
                                                 record.timeout, record.respawned)))


@functools.partial(jax.jit, static_argnums=(1, 4, 5))
def _childhood(key, config, params, genome, num_steps, phase_steps):
    keys = lifetime_keys(key, config.num_tasks)
    start = random_pose(keys.pose, config)
    state = init_state(config, decode(config, genome), at(start))
    _, record = simulate(keys.childhood, config, childhood_phase(config), params, childhood_task(config), state,
                         num_steps, phase_steps)
    return start, record


def childhood_trajectory(key: jax.Array, config: Config, params: LearningParams, genome,
                         num_steps: int) -> Trajectory:
    """The first ``num_steps`` steps of the LE-LS childhood that ``live(key, ...)`` lives (same draws)."""
    start, record = _childhood(key, config, params, jnp.asarray(genome), num_steps, config.childhood_steps)
    return _trajectory(start, record)


def _task(key, config, params, agent, index, num_steps):
    task = task_spec(config, index)
    state = init_state(config, agent, at(task.start))
    _, record = simulate(key, config, config.spec.adult, params, task, state, num_steps,
                         config.task_steps)
    return task.start, record


@functools.partial(jax.jit, static_argnums=(1, 5))
def _one_task(key, config, params, agent, index, num_steps):
    return _task(key, config, params, agent, index, num_steps)


@functools.partial(jax.jit, static_argnums=(1, 4))
def _all_tasks(keys, config, params, adult_agents, num_steps):
    return jax.vmap(lambda k, a, i: _task(k, config, params, a, i, num_steps))(
        keys, adult_agents, jnp.arange(config.num_tasks))


def task_trajectory(key: jax.Array, config: Config, params: LearningParams, agent: Agent, task: int,
                    num_steps: int) -> Trajectory:
    """``num_steps`` steps of task ``task`` (0-based) from ``agent`` (e.g. a task's final weights), as in adulthood."""
    start, record = _one_task(key, config, params, agent, jnp.int32(task), num_steps)
    return _trajectory(start, record)


def task_trajectories(key: jax.Array, config: Config, params: LearningParams, adult_agents: Agent,
                      num_steps: int) -> list[Trajectory]:
    """One path per task from each task's agent (``LifetimeResult.adult_agents``), in one vmapped program."""
    starts, records = _all_tasks(jax.random.split(key, config.num_tasks), config, params, adult_agents, num_steps)
    batch = _trajectory(starts, records)
    return [Trajectory(*(x[i] for x in batch)) for i in range(config.num_tasks)]


def force_expert(agent: Agent, expert) -> Agent:
    """``agent`` with a selector that always gives control to ``expert``."""
    k, n = agent.selector_actor.shape
    bias = jnp.where(jnp.arange(k) == expert, _FORCE, -_FORCE).astype(agent.selector_actor.dtype)
    return agent._replace(selector_actor=jnp.zeros((k, n), agent.selector_actor.dtype).at[:, -1].set(bias))


def probe_experts(key: jax.Array, config: Config, agent: Agent, num_starts: int = 8,
                  num_steps: int = 300) -> Trajectory:
    """Each expert alone in control (no learning, no noise) from ``num_starts`` random poses.

    Returns a Trajectory with leading axes (experts, starts, steps); the same start poses
    for every expert.
    """
    poses = jax.vmap(lambda k: random_pose(k, config))(jax.random.split(key, num_starts))
    starts, records = _probe_from(config, agent, poses, num_steps)
    return _trajectory(starts, records)


@functools.partial(jax.jit, static_argnums=0)
def _retina_points(config, pos, heading):
    return jax.vmap(lambda p, h: sample_points(config, Pose(p, h)))(pos, heading)


@functools.partial(jax.jit, static_argnums=0)
def _retina_colours(config, pos, heading):
    return floor_colour(config, _retina_points(config, pos, heading))


def retina_colours(config: Config, pos, heading) -> np.ndarray:
    """Floor colour (RED 0, GREEN 1, BLUE 2, NONE -1) under each retina point: (..., forward rows, lateral)."""
    pos, heading = np.asarray(pos, np.float32), np.asarray(heading, np.float32)
    colours = _retina_colours(config, pos.reshape(-1, 2), heading.reshape(-1))
    return np.asarray(colours).reshape(heading.shape + colours.shape[1:])


def retina_points(config: Config, pos, heading) -> np.ndarray:
    """World positions (..., forward rows, lateral, 2) of the retina points of poses (..., 2), (...)."""
    pos, heading = np.asarray(pos, np.float32), np.asarray(heading, np.float32)
    points = _retina_points(config, pos.reshape(-1, 2), heading.reshape(-1))
    return np.asarray(points).reshape(heading.shape + points.shape[1:])


def colour_reinforcers(config: Config, strength: float = 2.0) -> np.ndarray:
    """An LE-LS genome whose reinforcer k rewards colour k under the central receptors (MODEL.md's hand-made check).

    r_k = 2 sigmoid(strength * (number of central points seeing colour k)) - 1: 0 when the
    colour is not under the middle of the retina. Not evolved: a known input for the tour.
    """
    rows, lateral = len(config.retina_forward), len(config.retina_lateral)
    n = config.num_inputs + 1
    genome = np.zeros((config.num_experts, n), np.float32)
    for k in range(config.num_experts):
        weights = np.zeros((rows, lateral, 3), np.float32)
        weights[:, central_columns(config), k % 3] = strength
        genome[k, :-1] = weights.reshape(-1)
    return genome.reshape(-1)


def central_columns(config: Config) -> list[int]:
    """Indices of the retina's central lateral points (the two nearest the midline)."""
    lateral = np.abs(np.asarray(config.retina_lateral))
    return [int(i) for i in np.flatnonzero(lateral == lateral.min())]


def colour_shares(config: Config, trajectory: Trajectory, num_experts: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """What each expert follows: for each expert, the share of its control steps' central readings that are R, G, B, nothing.

    The readings are those of the central receptors (both rows, the lateral points nearest
    the midline) at the pose where the expert was chosen. Returns ``shares`` (K, 4), rows
    summing to 1 (NaN for an expert that never had control), and ``steps`` (K,) of control.
    Any leading axes of the trajectory are pooled.
    """
    k = np.asarray(trajectory.k).reshape(-1)
    num_experts = int(k.max()) + 1 if num_experts is None else num_experts
    colours = retina_colours(config, trajectory.seen_pos.reshape(-1, 2), trajectory.seen_heading.reshape(-1))
    central = colours[:, :, central_columns(config)].reshape(len(k), -1)  # (T, rows * central)
    seen = np.stack([(central == c).mean(1) for c in (0, 1, 2)] + [(central < 0).mean(1)], -1)  # (T, 4)
    steps = np.bincount(k, minlength=num_experts)[:num_experts]
    shares = np.full((num_experts, len(SEEN)), np.nan)
    for e in range(num_experts):
        if steps[e]:
            shares[e] = seen[k == e].mean(0)
    return shares, steps


def shares_table(shares: np.ndarray, steps: np.ndarray) -> str:
    """:func:`colour_shares` as a plain-text table (one row per expert)."""
    lines = [f"{'expert':>7} {'steps':>7} " + " ".join(f"{name:>8}" for name in SEEN)]
    for e, (row, n) in enumerate(zip(shares, steps)):
        cells = " ".join(f"{v:8.2f}" if np.isfinite(v) else f"{'-':>8}" for v in row)
        lines.append(f"{e + 1:>7} {int(n):>7} {cells}")
    return "\n".join(lines)


# --------------------------------------------------------------------------- specialisation

#: An expert follows colour c when, arriving at junctions where an edge of colour c leaves,
#: it takes that edge at least this often (claim 7; docs/CHILDHOOD.md). A robot that always
#: turns one way takes each colour half the time, so 0.75 needs the colour, not a side.
FOLLOW_CHOICE = 0.75
#: Advancing: at least this many cm in a step (half the top speed). A robot parked on a
#: line sees its colour all the time without following it.
FOLLOW_STEP = 1.0
#: A junction counts as passed when the robot, having come within NEAR cm of the vertex,
#: is FAR cm from it; the edge it took is the one nearest its direction from the vertex.
_NEAR, _FAR = 12.0, 25.0


class Specialisation(NamedTuple):
    """What each expert does alone (no learning, no noise) from the same starts before junctions.

    On this floor no colour runs straight: an edge is 40 cm long and ends at a junction
    where the two other colours leave at +-60 deg. Following a colour therefore means taking
    it at junctions, which is what composing experts in the tasks needs.
    """

    takes: np.ndarray  # (K, 3): share of junctions offering colour c at which the expert took c
    passed: np.ndarray  # (K,): share of junctions the expert passed (took any edge, or went straight on)
    following: np.ndarray  # (K, 3): share of steps with colour c under the retina's centre while advancing
    speed: np.ndarray  # (K,): mean cm per step
    turn: np.ndarray  # (K,): mean |turn| in degrees per step
    followed: np.ndarray  # (K,): the colour each expert follows (RED 0, GREEN 1, BLUE 2) or -1

    @property
    def num_colours(self) -> int:
        """How many distinct colours the experts follow."""
        return len(set(int(c) for c in self.followed) - {-1})


def probe_starts(config: Config, per_colour: int = 8) -> Pose:
    """Fixed probe starts: ``per_colour`` per colour, at the middles of the edges of that colour
    nearest the arena's centre, heading along the edge (both ways) towards a junction 20 cm
    ahead. Poses with a leading axis of 3 * per_colour, colours in order R, G, B."""
    a, h = config.edge_length, config.hex_apothem
    ox, oy = config.tiling_origin
    centre = config.arena_size / 2.0
    span = int(config.arena_size // a) + 4
    # Red edges are horizontal, centred at (ox + 1.5a + 1.5a m + 3a j, oy + m h) (arena.py);
    # colour k's edges are the red ones turned by k * 60 deg about the hexagon centre (ox, oy).
    red = np.array([(ox + 1.5 * a * (1 + m) + 3.0 * a * j, oy + m * h)
                    for m in range(-span, span + 1) for j in range(-span, span + 1)], np.float64)
    poses, headings = [], []
    for k in range(3):
        angle = k * np.pi / 3.0
        c, s = np.cos(angle), np.sin(angle)
        mid = np.stack([ox + c * (red[:, 0] - ox) - s * (red[:, 1] - oy),
                        oy + s * (red[:, 0] - ox) + c * (red[:, 1] - oy)], -1)
        nearest = mid[np.argsort(np.hypot(*(mid - centre).T), kind="stable")[: -(-per_colour // 2)]]
        for i in range(per_colour):
            poses.append(nearest[i // 2])
            headings.append((angle + np.pi * (i % 2)) % (2.0 * np.pi))
    return Pose(jnp.asarray(np.array(poses), jnp.float32), jnp.asarray(np.array(headings), jnp.float32))


def junction_choices(config: Config, path: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Which edge each probe run took at the junction ahead of its start.

    ``path`` has axes (..., starts, steps) and starts from :func:`probe_starts`. Returns the
    colour taken (..., starts) (-1: none, e.g. straight on or never passed) and the two
    colours offered there (starts, 2).
    """
    start, heading = path.seen_pos[..., 0, :], path.seen_heading[..., 0]
    direction = np.stack([np.cos(heading), np.sin(heading)], -1)
    vertex = start + 0.5 * config.edge_length * direction
    offset = path.pos - vertex[..., None, :]
    distance = np.hypot(offset[..., 0], offset[..., 1])
    near = np.maximum.accumulate(distance <= _NEAR, axis=-1)
    passed = near & (distance >= _FAR)
    first = np.argmax(passed, axis=-1)
    exit_offset = np.take_along_axis(offset, first[..., None, None], -2)[..., 0, :]
    bearing = np.arctan2(exit_offset[..., 1], exit_offset[..., 0])
    # The edges leaving the junction point at heading +- 60 deg; their colour is their direction mod 180.
    outgoing = heading[..., None] + np.array([np.pi / 3.0, -np.pi / 3.0])
    colours = np.round(np.mod(outgoing, np.pi) / (np.pi / 3.0)).astype(int) % 3
    error = np.abs(np.angle(np.exp(1j * (bearing[..., None] - outgoing))))
    nearest = error.argmin(-1)
    taken = np.take_along_axis(colours, nearest[..., None], -1)[..., 0]
    ok = passed.any(-1) & (error.min(-1) < np.pi / 6.0)
    return np.where(ok, taken, -1), np.where(passed.any(-1), 1, 0), colours


@functools.partial(jax.jit, static_argnums=(0, 3))
def _probe_from(config, agent, poses, num_steps):
    num_experts = agent.selector_actor.shape[0]
    params = config.learning_params()
    key = jax.random.key(0)  # unused: no choice is random under a forced selector, and no noise

    def run(expert, pose):
        state = init_state(config, force_expert(agent, expert), at(pose))
        _, record = simulate(key, config, PROBE, params, childhood_task(config), state, num_steps)
        return record

    records = jax.vmap(jax.vmap(run, (None, 0)), (0, None))(jnp.arange(num_experts), poses)
    starts = jax.tree.map(lambda x: jnp.broadcast_to(x, (num_experts,) + x.shape), poses)
    return starts, records


def specialisation(config: Config, agent: Agent, per_colour: int = 8, num_steps: int = 100) -> Specialisation:
    """Drive each expert of ``agent`` alone from :func:`probe_starts` for ``num_steps`` steps and measure it."""
    starts, records = _probe_from(config, agent, probe_starts(config, per_colour), num_steps)
    path = _trajectory(starts, records)  # (K, starts, steps)
    num_experts = path.k.shape[0]
    taken, passed, offered = junction_choices(config, path)  # (K, S), (K, S), (K, S, 2)
    takes = np.zeros((num_experts, 3))
    for c in range(3):
        available = (offered == c).any(-1)  # (K, S)
        takes[:, c] = ((taken == c) & available).sum(-1) / np.maximum(available.sum(-1), 1)
    colours = retina_colours(config, path.seen_pos, path.seen_heading)  # (K, S, T, rows, lateral)
    central = colours[..., central_columns(config)].reshape(path.k.shape + (-1,))
    seen = np.stack([(central == c).mean(-1) for c in (0, 1, 2)], -1)  # (K, S, T, 3)
    advance = np.hypot(*np.moveaxis(path.pos - path.seen_pos, -1, 0))  # (K, S, T)
    turn = np.angle(np.exp(1j * (path.heading - path.seen_heading)))
    following = (seen * (advance >= FOLLOW_STEP)[..., None]).reshape(num_experts, -1, 3).mean(1)
    followed = np.where(takes.max(1) >= FOLLOW_CHOICE, takes.argmax(1), -1)
    return Specialisation(takes=takes, passed=passed.mean(-1), following=following,
                          speed=advance.reshape(num_experts, -1).mean(1),
                          turn=np.degrees(np.abs(turn)).reshape(num_experts, -1).mean(1), followed=followed)


def specialisation_table(spec: Specialisation) -> str:
    """:func:`specialisation` as a plain-text table (one row per expert)."""
    names = ("red", "green", "blue")
    lines = [f"{'expert':>7} {'follows':>8} " + " ".join(f"{'takes ' + c:>11}" for c in names)
             + f" {'passed':>7} {'cm/step':>8} {'deg/step':>9}"]
    for e in range(len(spec.followed)):
        name = names[spec.followed[e]] if spec.followed[e] >= 0 else "-"
        lines.append(f"{e + 1:>7} {name:>8} " + " ".join(f"{v:11.2f}" for v in spec.takes[e])
                     + f" {spec.passed[e]:7.2f} {spec.speed[e]:8.2f} {spec.turn[e]:9.1f}")
    return "\n".join(lines)


# ----------------------------------------------------------------------------- childhoods of many genomes

#: Samples of the pose (for the time on walls) and of control shares over a childhood.
NUM_PIECES = 200


def make_childhoods(config, num_pieces: int = NUM_PIECES, jit: bool = True):
    """A jitted ``childhoods(keys, params, genome)`` over lanes: the agents after childhood and per-piece records.

    Records per lane: steps each expert led in each piece (pieces, K), whether the robot is
    on a wall at the end of each piece (pieces,), random poses after a wall per piece.
    """
    phase = childhood_phase(config)
    piece_steps = config.childhood_steps // num_pieces
    r, size = config.robot_radius, config.arena_size

    def one(key, params, genome):
        keys = lifetime_keys(key, config.num_tasks)
        state = for_phase(config, phase, init_state(config, decode(config, genome), at(random_pose(keys.pose, config))))

        def piece(state, _):
            state, curves = run_phase(keys.childhood, config, phase, params, childhood_task(config), state,
                                      piece_steps, phase_steps=config.childhood_steps, num_bins=1)
            on_wall = jnp.any((state.world.pose.pos <= r + 1e-3) | (state.world.pose.pos >= size - r - 1e-3))
            respawns = jnp.int32(0) if curves.respawns is None else curves.respawns[0]
            return state, (curves.selections[0], on_wall, respawns)

        state, records = jax.lax.scan(piece, state, None, length=num_pieces)
        return state.agent, records

    return jax.jit(jax.vmap(one, (0, 0, None))) if jit else one


def grown_agents(config, genomes, key: int):
    """The experts each genome ends childhood with (LE-LS: a fresh childhood each, keys from ``key``), and the
    childhood records of :func:`make_childhoods` (None without a childhood)."""
    genomes = jnp.asarray(genomes)
    if not config.spec.has_childhood:
        return jax.vmap(lambda g: decode(config, g))(genomes), None
    keys = jax.random.split(jax.random.key(key), len(genomes))
    one = make_childhoods(config, jit=False)
    params = config.learning_params()
    agents, records = jax.jit(jax.vmap(lambda k, g: one(k, params, g)))(keys, genomes)
    return agents, jax.device_get(records)
