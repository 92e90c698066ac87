"""Plain NumPy reference of one lifetime, written step by step from MODEL.md; slow, for tests and benchmarks.

Everything here is float64 NumPy and ordinary Python loops, one time step at a time, so it
can serve as an independent check of the JAX implementation. It follows MODEL.md literally:

* the floor colour of a point is found by brute force, measuring the distance from the
  point to every edge segment of the hexagons around it;
* the retina samples that colour at its 12 points;
* the robot turns, moves and is clamped to the walls;
* each step picks an expert, learns from the previous transition, acts and moves (:class:`Arena`; a world
  of discrete actions: :mod:`imrl_jax.agent.reference_discrete`).

Public: :func:`floor_colour`, :func:`observe`, :func:`move`, :class:`Arena`, :func:`run_phase`, :func:`live`.
Weights are dicts of float64 arrays with keys ``reinforcer`` (K, 37), ``actor`` (K, 2, 37), ``evaluator``
(K, 37), ``selector_actor`` (K, 37) and ``selector_critic`` (37,).
"""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.conditions import ADULT_EVOLVED_SELECTOR, ADULT_LEARNING_SELECTOR, ADULT_SINGLE_EXPERT, CHILDHOOD, Phase
from imrl_jax.genome import get_part

NO_COLOUR, RED, GREEN, BLUE = -1, 0, 1, 2

#: The phases by name (a phase may also be given as a :class:`~imrl_jax.conditions.Phase`).
PHASES = {"childhood": CHILDHOOD, "adult-ls": ADULT_LEARNING_SELECTOR, "adult-es": ADULT_EVOLVED_SELECTOR,
          "sle": ADULT_SINGLE_EXPERT}

WEIGHT_KEYS = ("reinforcer", "actor", "evaluator", "selector_actor", "selector_critic")
#: What a life carries from phase to phase: the weights, and what genome parts add (expression, a second reinforcer).
CARRIED = (*WEIGHT_KEYS, "expressed", "second_reinforcer")


# --------------------------------------------------------------------------- floor


def _hexagon_centres(config):
    """Centres of every hexagon that has an edge in (or near) the arena.

    Centres are origin + i*(1.5 a, apothem) + j*(0, 2 apothem) for integers i, j
    (MODEL.md: (160, 200) + i*(60, 20 sqrt 3) + j*(0, 40 sqrt 3) for a = 40).
    """
    a = config.edge_length
    apothem = a * math.sqrt(3.0) / 2.0
    ox, oy = config.tiling_origin
    low, high = -2.0 * a, config.arena_size + 2.0 * a
    centres = []
    i_low = int(math.floor((low - ox) / (1.5 * a))) - 1
    i_high = int(math.ceil((high - ox) / (1.5 * a))) + 1
    for i in range(i_low, i_high + 1):
        cx = ox + i * 1.5 * a
        column_y = oy + i * apothem
        j_low = int(math.floor((low - column_y) / (2.0 * apothem))) - 1
        j_high = int(math.ceil((high - column_y) / (2.0 * apothem))) + 1
        for j in range(j_low, j_high + 1):
            cy = column_y + j * 2.0 * apothem
            if low <= cx <= high and low <= cy <= high:
                centres.append((cx, cy))
    return centres


def _edge_colour(start, end):
    """Colour of an edge from its direction: 0 deg red, 60 deg green, 120 deg blue."""
    angle = math.degrees(math.atan2(end[1] - start[1], end[0] - start[0])) % 180.0
    sixties = int(round(angle / 60.0)) % 3
    return {0: RED, 1: GREEN, 2: BLUE}[sixties]


_EDGE_CACHE: dict = {}


def _all_edges(config):
    """Start points (E, 2), end points (E, 2), colours (E,) and hexagon centres (E, 2) of
    the six edges of every hexagon around the arena (shared edges appear twice)."""
    cache_key = (config.edge_length, tuple(config.tiling_origin), config.arena_size)
    if cache_key not in _EDGE_CACHE:
        a = config.edge_length
        starts, ends, colours, centres = [], [], [], []
        for cx, cy in _hexagon_centres(config):
            vertices = [(cx + a * math.cos(math.radians(60.0 * k)), cy + a * math.sin(math.radians(60.0 * k)))
                        for k in range(6)]
            for k in range(6):
                start, end = vertices[k], vertices[(k + 1) % 6]
                starts.append(start)
                ends.append(end)
                colours.append(_edge_colour(start, end))
                centres.append((cx, cy))
        _EDGE_CACHE[cache_key] = (np.array(starts), np.array(ends), np.array(colours), np.array(centres))
    return _EDGE_CACHE[cache_key]


def _edges_near(config, p):
    """(starts, ends, colours) of the edges of every hexagon whose centre is within two
    edge lengths of p (this includes the hexagon that contains p, whose edges are the
    nearest ones)."""
    starts, ends, colours, centres = _all_edges(config)
    near = np.hypot(centres[:, 0] - p[0], centres[:, 1] - p[1]) <= 2.0 * config.edge_length
    return starts[near], ends[near], colours[near]


def _distances_to_segments(p, starts, ends):
    """Euclidean distance from point p to each segment starts[i]-ends[i]."""
    d = ends - starts
    length2 = np.sum(d * d, axis=1)
    t = ((p[0] - starts[:, 0]) * d[:, 0] + (p[1] - starts[:, 1]) * d[:, 1]) / length2
    t = np.clip(t, 0.0, 1.0)
    closest_x = starts[:, 0] + t * d[:, 0]
    closest_y = starts[:, 1] + t * d[:, 1]
    return np.hypot(p[0] - closest_x, p[1] - closest_y)


def floor_colour(config, p) -> int:
    """Colour of the floor under point p = (x, y): -1 none, 0 red, 1 green, 2 blue.

    The nearest edge segment decides; distances within ``colour_tie_tolerance`` of the
    nearest count as a tie, won by red, then green, then blue. The point is on that edge
    when its distance is <= ``line_half_width``. Strictly outside the arena: no colour.
    """
    x, y = float(p[0]), float(p[1])
    if x < 0.0 or x > config.arena_size or y < 0.0 or y > config.arena_size:
        return NO_COLOUR
    starts, ends, colours = _edges_near(config, (x, y))
    distances = _distances_to_segments((x, y), starts, ends)
    nearest = distances.min()
    if nearest > config.line_half_width:
        return NO_COLOUR
    tied = colours[distances <= nearest + config.colour_tie_tolerance]
    for colour in (RED, GREEN, BLUE):
        if colour in tied:
            return colour
    raise AssertionError("unreachable")


# --------------------------------------------------------------------------- retina and body


def observe(config, x, y, heading) -> np.ndarray:
    """The retina: 3 binary receptors (R, G, B) per point, order [forward][lateral][RGB]."""
    n_lat = len(config.retina_lateral)
    retina = np.zeros(3 * n_lat * len(config.retina_forward), dtype=np.float64)
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    for fi, f in enumerate(config.retina_forward):
        for li, lateral in enumerate(config.retina_lateral):
            px = x + f * cos_h + lateral * (-sin_h)
            py = y + f * sin_h + lateral * cos_h
            colour = floor_colour(config, (px, py))
            if colour != NO_COLOUR:
                retina[3 * (fi * n_lat + li) + colour] = 1.0
    return retina


def move(config, x, y, heading, a0, a1):
    """Turn by (a0 - 0.5) * 2 * max_turn, then go max_speed * a1 forward, then clamp to the walls."""
    heading = heading + (a0 - 0.5) * 2.0 * math.radians(config.max_turn_deg)
    heading = float(np.mod(heading, 2.0 * math.pi))
    x = x + config.max_speed * a1 * math.cos(heading)
    y = y + config.max_speed * a1 * math.sin(heading)
    low, high = config.robot_radius, config.arena_size - config.robot_radius
    x = min(max(x, low), high)
    y = min(max(y, low), high)
    return x, y, heading


# --------------------------------------------------------------------------- networks


def _sigmoid(v):
    return 1.0 / (1.0 + np.exp(-v))


def _with_bias(x):
    return np.concatenate([x, [1.0]])


def _choose_expert(s, u):
    """Expert k with probability s_k / sum(s): the first k with u * sum(s) < cumsum(s)[k]."""
    cumulative = np.cumsum(s)
    total = cumulative[-1]
    k = 0
    for j in range(len(s) - 1):
        if cumulative[j] <= u * total:
            k += 1
    return k


def _copy_weights(weights):
    return {key: np.array(weights[key], dtype=np.float64, copy=True) for key in CARRIED if key in weights}


def zero_weights(config, num_experts):
    """All weights 0 for ``num_experts`` experts (MODEL.md: learned weights start at 0), but (in the arena)
    the actors' speed unit's bias: config.initial_speed_bias; a discrete world's actors have a unit per action."""
    n = config.num_inputs + 1
    actor = np.zeros((num_experts, config.num_actor_units, n))
    if config.world == "arena":  # a discrete world's actions start alike
        actor[:, 1, -1] = config.initial_speed_bias
    return {
        "reinforcer": np.zeros((num_experts, n)),
        "actor": actor,
        "evaluator": np.zeros((num_experts, n)),
        "selector_actor": np.zeros((num_experts, n)),
        "selector_critic": np.zeros((n,)),
    }


def decode(config, genome):
    """The weights a genome encodes for config.condition (its networks one after the other); the rest are 0."""
    genome = np.asarray(genome, dtype=np.float64)
    weights = zero_weights(config, config.num_lane_experts)
    if genome.size != config.num_genes:
        raise ValueError(f"genome: {config.condition} has {config.num_genes} genes, got {genome.size}")
    start = 0
    for name in config.spec.genome:  # each part's NumPy twin puts its genes in place (genome.PARTS)
        part = get_part(name)
        shape = part.shape(config.num_lane_experts, config.num_inputs + 1, config.num_actor_units)
        size = int(np.prod(shape))
        part.reference_decode(config, weights, genome[start:start + size].reshape(shape))
        start += size
    return weights



def start_life(config, genome):
    """The decoded genome, and the config and childhood options its parts set before a life (``reference_life``)."""
    grown, options = decode(config, genome), {}
    for part in (get_part(name) for name in config.spec.genome):
        if part.reference_life is not None:
            config, more = part.reference_life(config, grown)
            options.update(more)
    return config, grown, options


def task_weights(config, grown):
    """The weights a task starts from: ``grown``, with the networks the condition resets back at their start."""
    weights, fresh = _copy_weights(grown), zero_weights(config, config.num_lane_experts)
    weights.update({network: fresh[network] for network in config.spec.reset})
    return weights

# --------------------------------------------------------------------------- one phase


class Arena:
    """The robot in the arena, as :func:`run_phase` moves it: its retina, its noisy command, its move, the walls
    (respawns in childhood), the target and the timeout. Another world's twin has the same methods."""

    def __init__(self, config, phase, pose, task, spawn, phase_steps):
        self.config, self.phase_steps, self.trial_steps, self.pinned = config, phase_steps, 0, 0
        self.respawn = phase.intrinsic and config.childhood_walls == "respawn"
        self.spawn = np.asarray(spawn, dtype=np.float64) if self.respawn else None
        self.start = self.target = None
        if phase.has_target:
            if task is None:
                raise ValueError("adult phases need a task")
            spec = config.tasks[task]
            self.start = (float(spec.start[0]), float(spec.start[1]), math.radians(spec.heading_deg))
            self.target = (float(spec.target[0]), float(spec.target[1]))
        self.x, self.y, self.heading = float(pose[0]), float(pose[1]), float(pose[2])
        self.path = {"x": [], "y": [], "heading": []}  # the pose after each step

    def observe(self):
        return observe(self.config, self.x, self.y, self.heading)

    def act(self, o, explores, t, z):
        """a = clip(o + sigma_t z, 0, 1), sigma_t = noise_std * max(1 - t / phase_steps, 0) where it explores."""
        sigma = self.config.noise_std * max(1.0 - t / self.phase_steps, 0.0) if explores else 0.0
        return np.clip(o + sigma * z, 0.0, 1.0)

    def step(self, a, t):
        """Turn, move, clamp; then the walls (respawn), the target and the timeout: (reached, timeout, respawned)."""
        config = self.config
        x, y, heading = move(config, self.x, self.y, self.heading, float(a[0]), float(a[1]))
        reached = timeout = respawned = False
        if self.respawn:
            r, size = config.robot_radius, config.arena_size
            on_wall = x <= r or x >= size - r or y <= r or y >= size - r
            self.pinned = self.pinned + 1 if on_wall else 0
            if self.pinned >= config.wall_respawn_steps:
                respawned = True
                self.pinned = 0
                x = r + (size - 2.0 * r) * self.spawn[t, 0]
                y = r + (size - 2.0 * r) * self.spawn[t, 1]
                heading = 2.0 * math.pi * self.spawn[t, 2]
        if self.target is not None:
            self.trial_steps += 1
            if math.hypot(x - self.target[0], y - self.target[1]) <= config.target_radius:
                reached = True
            elif self.trial_steps >= config.trial_timeout:
                timeout = True
            if reached or timeout:
                x, y, heading = self.start
                self.trial_steps = 0
        self.x, self.y, self.heading = x, y, heading
        for name, value in zip(("x", "y", "heading"), (x, y, heading)):
            self.path[name].append(value)
        return reached, timeout, respawned

    def record(self) -> dict:
        return {name: np.array(values, dtype=np.float64) for name, values in self.path.items()}


def run_phase(config, phase, weights, pose, u, z, task=None, phase_steps=None, spawn=None,
              learning_steps=None, body=None) -> dict:
    """Run one phase step by step (MODEL.md "Acting" and "Learning"; docs/CHILDHOOD.md options).

    phase: a :class:`~imrl_jax.conditions.Phase` or its name in :data:`PHASES` ("childhood",
    "adult-ls", "adult-es", "sle"); a phase with intrinsic rewards takes the config's childhood
    options and values. pose: (x, y, heading radians).
    u (T,) uniform draws for the expert choice, z (T, 2) normal draws for the action noise,
    spawn (T, 3) uniform draws of a random pose (childhood with config.childhood_walls
    "respawn" only). task: task index for the adult phases (None in childhood).
    phase_steps: the length of the noise annealing (default T). learning_steps: steps after which
    nothing learns or explores (an evolved childhood length; default all). body: the agent in its world
    (:class:`Arena` at pose by default; another world's twin holds its own start, task and draws). Returns the
    body's record after each step (the arena's: the pose), the experts chosen, the reach/timeout/respawn
    flags, the final weights and the number of reaches.
    """
    if not isinstance(phase, Phase):
        if phase not in PHASES:
            raise ValueError(f"unknown phase {phase!r}")
        phase = PHASES[phase]
    u = np.asarray(u, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    num_steps = u.shape[0]
    if phase_steps is None:
        phase_steps = num_steps

    w = _copy_weights(weights)
    num_experts = w["selector_actor"].shape[0]
    n = w["selector_critic"].shape[0]

    experts_learn, selector_learns = phase.experts_learn, phase.selector_learns
    learning = lambda t: learning_steps is None or t < learning_steps  # noqa: E731

    gamma = config.gamma
    childhood = phase.intrinsic
    # Childhood learns with its own trace decay and selector rates.
    decay = config.gamma * (config.childhood_trace_lambda if childhood else config.trace_lambda)
    eta_selector_actor = config.childhood_eta_selector_actor if childhood else config.eta_selector_actor
    eta_selector_critic = config.childhood_eta_selector_critic if childhood else config.eta_selector_critic
    progress = childhood and config.childhood_selector_reward == "progress"
    baseline = np.zeros(num_experts)  # each expert's running mean surprise ("progress")
    if body is None:
        body = Arena(config, phase, pose, task, spawn, phase_steps)
    units = w["actor"].shape[1]  # the arena's (turn, speed), or a discrete world's actions

    # Traces: one set for the expert in control, one for the selector; 0 at the phase start.
    trace_v = np.zeros(n)
    trace_w = np.zeros((units, n))
    trace_u = np.zeros(n)
    trace_s = np.zeros((num_experts, n))

    # What the previous step left behind.
    prev_valid = prev_reached = False
    prev_xb = prev_a = prev_o = None
    prev_k = -1

    out_k = np.zeros(num_steps, dtype=np.int64)
    out_reached, out_timeout, out_respawned = (np.zeros(num_steps, dtype=bool) for _ in range(3))

    # The selector's option (docs/TIMESCALE.md): chosen at x~ opt_xb with outputs opt_s; its reward so far
    # sum_i gamma^i r_{i+1}, gamma^tau for its tau transitions, whether its expert learned on one of them (the
    # childhood selector's reward exists), and gamma^tau of the option last learned from (the traces' decay).
    # With selector_period 1 every option lasts one step: the paper's per-step rules.
    period = config.selector_period
    opt_xb = opt_s = None
    opt_reward, opt_discount, opt_learned, opt_steps, opt_trace_discount = 0.0, 1.0, False, 0, 1.0

    for t in range(num_steps):
        # 1. What the robot sees now.
        xb = _with_bias(body.observe())

        # 2. The selector picks an expert (weights before this step's learning), where its option ends.
        s = _sigmoid(w["selector_actor"] @ xb)
        if "expressed" in w:  # an unexpressed expert's output is 0: it is never chosen
            s = s * w["expressed"]
        choose = (not prev_valid) or prev_reached or opt_steps + 1 >= period
        if config.selector_termination == "colour" and not choose:
            seen_now, seen_before = xb[:-1].reshape(-1, 3).max(0), prev_xb[:-1].reshape(-1, 3).max(0)
            choose = bool(np.any(seen_now > seen_before))  # a colour came into view
        k = _choose_expert(s, u[t]) if choose else prev_k

        # 3. Learning from the transition t-1 -> t.
        terminal = prev_valid and prev_reached
        same_expert = prev_valid and k == prev_k
        expert_delta = None
        if prev_valid:
            if experts_learn and learning(t) and same_expert:
                kp = prev_k
                discount = gamma
                if phase.evaluation:  # evolved evaluators: the change of the fixed evaluation
                    reward = 0.0
                    discount = gamma if phase.evaluation == "discounted" else 1.0
                elif childhood:
                    reward = 2.0 * _sigmoid(w["reinforcer"][kp] @ xb) - 1.0
                    if "second_reinforcer" in w:  # two units: the mean of their rewards
                        reward = 0.5 * (reward + (2.0 * _sigmoid(w["second_reinforcer"][kp] @ xb) - 1.0))
                else:
                    reward = 1.0 if prev_reached else 0.0
                value_now = w["evaluator"][kp] @ xb
                value_prev = w["evaluator"][kp] @ prev_xb
                if terminal:
                    expert_delta = reward - value_prev
                else:
                    expert_delta = reward + discount * value_now - value_prev
                trace_v = decay * trace_v + prev_xb
                slope = (prev_a - prev_o) * prev_o * (1.0 - prev_o)
                trace_w = decay * trace_w + np.outer(slope, prev_xb)
                if not phase.evaluation:  # an evolved evaluator does not learn
                    w["evaluator"][kp] = w["evaluator"][kp] + config.eta_evaluator * expert_delta * trace_v
                w["actor"][kp] = w["actor"][kp] + config.eta_actor * expert_delta * trace_w

            selector_reward = None
            if selector_learns and learning(t):
                if childhood:
                    if same_expert:
                        selector_reward = expert_delta
                        if progress:
                            selector_reward = expert_delta - baseline[prev_k]
                            baseline[prev_k] += config.progress_rate * (expert_delta - baseline[prev_k])
                else:
                    selector_reward = 1.0 if prev_reached else 0.0
                # Semi-Markov TD: the option's reward is summed, discounted, over its steps; it learns when it ends.
                opt_reward += opt_discount * (0.0 if selector_reward is None else selector_reward)
                opt_discount *= gamma
                opt_learned = opt_learned or selector_reward is not None
            if selector_learns and learning(t) and choose and opt_learned:
                u_now = w["selector_critic"] @ xb
                u_start = w["selector_critic"] @ opt_xb
                if terminal:
                    selector_delta = opt_reward - u_start
                else:
                    selector_delta = opt_reward + opt_discount * u_now - u_start
                selector_decay = opt_trace_discount * (config.childhood_trace_lambda if childhood
                                                       else config.trace_lambda)
                trace_u = selector_decay * trace_u + opt_xb
                onehot = np.zeros(num_experts)
                onehot[prev_k] = 1.0
                slope = (onehot - opt_s) * opt_s * (1.0 - opt_s)
                trace_s = selector_decay * trace_s + np.outer(slope, opt_xb)
                w["selector_critic"] = w["selector_critic"] + eta_selector_critic * selector_delta * trace_u
                w["selector_actor"] = w["selector_actor"] + eta_selector_actor * selector_delta * trace_s
                opt_trace_discount = opt_discount

        # Trace clears after this step's learning.
        if (not prev_valid) or (not same_expert) or terminal:
            trace_v = np.zeros(n)
            trace_w = np.zeros((units, n))
        if (not prev_valid) or terminal:
            trace_u = np.zeros(n)
            trace_s = np.zeros((num_experts, n))

        # 4. Act with the expert in control (weights after this step's learning), exploring where the phase does.
        o = _sigmoid(w["actor"][k] @ xb)
        a = body.act(o, phase.noisy and learning(t), t, z[t])

        # 5. The world's step (the arena's: turn, move, clamp; then the walls, the target and the timeout).
        reached, timeout, respawned = body.step(a, t)
        out_k[t], out_reached[t], out_timeout[t], out_respawned[t] = k, reached, timeout, respawned

        prev_valid = not (timeout or respawned)
        prev_xb, prev_k, prev_a, prev_o = xb, k, a, o
        if choose:  # a new option starts at x~_t
            opt_xb, opt_s = xb, s
            opt_reward, opt_discount, opt_learned, opt_steps = 0.0, 1.0, False, 0
        else:
            opt_steps += 1
        prev_reached = reached

    return {**body.record(), "k": out_k, "reached": out_reached, "timeout": out_timeout, "respawned": out_respawned,
            "weights": w, "reaches": int(out_reached.sum())}


# --------------------------------------------------------------------------- one life


def _task_pose(config, i):
    spec = config.tasks[i]
    return (float(spec.start[0]), float(spec.start[1]), math.radians(spec.heading_deg))


def live(config, genome, start_pose, childhood_u, childhood_z, task_u, task_z, childhood_spawn=None) -> dict:
    """One whole life of config.condition (MODEL.md "Life" and "Conditions").

    start_pose: childhood start (x, y, heading radians), used by LE-LS only.
    childhood_u (childhood_steps,), childhood_z (childhood_steps, 2): childhood draws;
    childhood_spawn (childhood_steps, 3) with config.childhood_walls "respawn".
    task_u (tasks, task_steps), task_z (tasks, task_steps, 2): the draws of each task.
    """
    config, grown, options = start_life(config, genome)  # evolved values: the config; a childhood's length
    spec = config.spec
    if spec.has_childhood:
        child = run_phase(config, spec.childhood, grown, start_pose, childhood_u, childhood_z,
                          task=None, phase_steps=config.childhood_steps, spawn=childhood_spawn,
                          **options)
        grown = child["weights"]

    task_u = np.asarray(task_u, dtype=np.float64)
    task_z = np.asarray(task_z, dtype=np.float64)
    theoretical = config.theoretical_max()
    reaches = np.zeros(config.num_tasks, dtype=np.int64)
    ended = []  # each task's weights at its end
    for i in range(config.num_tasks):
        result = run_phase(config, spec.adult, task_weights(config, grown), _task_pose(config, i), task_u[i],
                           task_z[i], task=i, phase_steps=config.adult_noise_steps)
        reaches[i] = result["reaches"]
        ended.append(result["weights"])

    performance = reaches / np.asarray(theoretical, dtype=np.float64)
    return {"reaches": reaches, "performance": performance, "fitness": float(performance.mean()),
            "childhood_weights": _copy_weights(grown), "task_weights": ended}


def live_with(config, genome, draws) -> dict:
    """:func:`live` with the draws of a JAX life (a :class:`~imrl_jax.agent.lifetime.LifeDraws`: pose, childhood, tasks)."""
    pose, child, tasks = draws.pose, draws.childhood, draws.tasks
    start = (*np.asarray(pose.pos, np.float64), float(pose.heading))
    spawn = None if child.spawn is None else np.asarray(child.spawn, np.float64)
    return live(config, np.asarray(genome, np.float64), start, np.asarray(child.u, np.float64),
                np.asarray(child.z, np.float64), np.asarray(tasks.u, np.float64), np.asarray(tasks.z, np.float64),
                childhood_spawn=spawn)


#: Known inputs for checks against the reference (the tests and ``imrl_jax.commands.gpu_check``).
#: One task whose target lies 40 cm straight ahead of the start, 85 cm from the east wall:
#: reaches, timeouts and wall contacts all happen within a few hundred steps.
SHORT_TASK_FIELDS = dict(start=(300.0, 200.0), heading_deg=0.0, target=(340.0, 200.0))
#: Learning values other than the paper's, every rule's extension switched on (traces, per-network rates).
EXTENDED = dict(trace_lambda=0.9, eta_actor=0.05, eta_evaluator=0.02, eta_selector_actor=0.5,
                eta_selector_critic=0.003, childhood_trace_lambda=0.8, childhood_eta_selector_actor=0.2,
                childhood_eta_selector_critic=0.02)


def hand_experts(n):
    """Expert actors (3, 2, n): 0 drives straight at full speed, 1 and 2 turn left / right slowly."""
    actor = np.zeros((3, 2, n))
    actor[0, 1, -1] = 6.0  # speed unit saturated: 2 cm per step
    actor[1, 0, -1], actor[1, 1, -1] = 2.0, 0.5
    actor[2, 0, -1], actor[2, 1, -1] = -2.0, 0.5
    return actor
