"""The arena of section 2 and MODEL.md "Arena and floor", "Robot": floor colours, walls, moves.

The floor is a flat-top hexagonal tiling whose edges are coloured by direction (0 deg red,
60 deg green, 120 deg blue). Every colour family is the red family turned by a multiple of
60 deg about a hexagon centre, so one closed-form distance to the nearest red edge, applied
to the point turned back, gives the distance to every colour.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from imrl_jax.config import Config

RED, GREEN, BLUE, NONE = 0, 1, 2, -1


class Pose(NamedTuple):
    """Robot centre (x, y) in cm and heading in radians."""

    pos: jnp.ndarray  # (2,)
    heading: jnp.ndarray  # ()


def _red_distance_sq(config: Config, x: jnp.ndarray, y: jnp.ndarray, round_even=jnp.round) -> jnp.ndarray:
    """Squared distance from points (x, y) to the nearest red edge on the nearest red line.

    ``round_even`` rounds half to even; the GPU kernel passes its own (see kernel.py).
    """
    a = config.edge_length
    h = config.hex_apothem
    ox, oy = config.tiling_origin
    # Horizontal edges lie on the lines y = oy + m*h; on line m they are segments of
    # length a centred every 3a, shifted by 1.5a per line.  Lines are 2h/sqrt(3) > 30 cm
    # apart, so for a point within a line width only its nearest line matters.
    m = round_even((y - oy) / h)
    dy = y - oy - m * h
    u = x - ox - 1.5 * a - 1.5 * a * m
    # u minus the nearest multiple of 3a: exact (the difference is a multiple of u's ulp),
    # and unlike jnp.mod (a per-element fmod call on CPU) it vectorises.
    u = u - 3.0 * a * round_even(u / (3.0 * a))
    dx = jnp.maximum(jnp.abs(u) - 0.5 * a, 0.0)
    return dx * dx + dy * dy


def _distances(config: Config, x: jnp.ndarray, y: jnp.ndarray, outside: jnp.ndarray,
               round_even=jnp.round) -> tuple[jnp.ndarray, ...]:
    """Distances from points (x, y) to the nearest red, green and blue edge (one array each).

    Exact where the distance is below half the spacing of parallel lines (about 17 cm),
    which is all that colour decisions use. Points where ``outside`` is True get an
    infinite distance.
    """
    ox, oy = config.tiling_origin
    qx, qy = x - ox, y - oy
    dists = []
    for k in range(3):  # colour k's edges are the red ones turned by k*60 deg
        c, s = math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)
        d2 = _red_distance_sq(config, c * qx + s * qy + ox, -s * qx + c * qy + oy, round_even)
        dists.append(jnp.sqrt(jnp.where(outside, jnp.inf, d2)))
    return tuple(dists)


def floor_colour_xy(config: Config, x: jnp.ndarray, y: jnp.ndarray, round_even=jnp.round) -> jnp.ndarray:
    """:func:`floor_colour` of points given as separate coordinate arrays x, y (``round_even``: half to even)."""
    # Outside the arena is infinitely far from every edge. Folding this test into the
    # distances (each an expensive kernel XLA computes once) keeps the pose out of the
    # kernels that read the colours, which XLA would otherwise recompute it in.
    outside = (x < 0.0) | (x > config.arena_size) | (y < 0.0) | (y > config.arena_size)
    red, green, blue = _distances(config, x, y, outside, round_even)
    d_min = jnp.minimum(jnp.minimum(red, green), blue)
    # The nearest edge wins; an exact tie goes to red, then green, then blue.
    near = d_min + config.colour_tie_tolerance
    colour = jnp.where(red <= near, RED, jnp.where(green <= near, GREEN, BLUE)).astype(jnp.int32)
    return jnp.where(d_min <= config.line_half_width, colour, NONE)


def floor_colour(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Colour index of the floor at points (..., 2): RED 0, GREEN 1, BLUE 2 or NONE -1.

    A point is on an edge within ``line_half_width``; the nearest edge wins and an exact
    tie (within ``colour_tie_tolerance``) goes to red, then green, then blue. Points
    outside the arena see no colour.
    """
    return floor_colour_xy(config, p[..., 0], p[..., 1])


def heading_vector(heading: jnp.ndarray) -> jnp.ndarray:
    """(cos, sin) of a heading: the robot's forward direction."""
    return jnp.stack([jnp.cos(heading), jnp.sin(heading)])


def turn(config: Config, heading, turn_output):
    """The new heading: turn by (a0 - 0.5) * 2 * max_turn, kept in [0, 2pi)."""
    heading = heading + (turn_output - 0.5) * 2.0 * math.radians(config.max_turn_deg)
    # Keeping the heading in [0, 2pi) keeps float32 precise over 150,000 steps of turning.
    # The same values as jnp.mod (a turn is less than a full circle), without its fmod call.
    full = 2.0 * math.pi
    return jnp.where(heading < 0.0, heading + full, jnp.where(heading >= full, heading - full, heading))


def advance(config: Config, pos, direction, speed_output):
    """The new position: advance max_speed * a1 along the heading's (cos, sin), then clamp to the walls.

    ``pos`` and ``direction`` are (2,) arrays, or (x, y) and (cos, sin) pairs of scalars
    (the GPU kernel's registers); the same arithmetic on each coordinate.
    """
    step = config.max_speed * speed_output
    r = config.robot_radius
    return jax.tree.map(lambda p, d: jnp.clip(p + step * d, r, config.arena_size - r), pos, direction)


def move(config: Config, pose: Pose, action: jnp.ndarray) -> Pose:
    """Turn by (a0 - 0.5) * 2 * max_turn, then advance max_speed * a1, then clamp (MODEL.md "Robot")."""
    heading = turn(config, pose.heading, action[0])
    return Pose(advance(config, pose.pos, heading_vector(heading), action[1]), heading)


def _combine(values, pair, array):
    """Both coordinates' values combined: ``pair(x, y)`` for a pair of scalars, ``array(v)`` for a (2,) array."""
    return pair(*values) if isinstance(values, tuple) else array(values)


def on_wall(config: Config, pos):
    """Whether the robot touches a wall (the clamp holds its centre at the border); ``pos`` as in :func:`advance`."""
    r, size = config.robot_radius, config.arena_size
    touching = jax.tree.map(lambda p: (p <= r) | (p >= size - r), pos)
    return _combine(touching, jnp.logical_or, jnp.any)


def spawn_pose(config: Config, position_draws, heading_draw):
    """A uniform pose from uniform draws in [0, 1): position in [r, size - r]^2, heading in [0, 2pi).

    ``position_draws``: a (2,) array, or a pair of scalars (the position comes back alike).
    """
    r, size = config.robot_radius, config.arena_size
    return jax.tree.map(lambda u: r + (size - 2.0 * r) * u, position_draws), 2.0 * math.pi * heading_draw


def trial_ends(config: Config, pos, target, trial_step):
    """(reached, timeout): the centre within the target's radius (reward 1), or the trial's steps used up.

    ``pos`` and ``target`` as in :func:`advance`.
    """
    squares = jax.tree.map(lambda p, t: (p - t) ** 2, pos, target)
    reached = _combine(squares, jnp.add, jnp.sum) <= config.target_radius ** 2
    return reached, ~reached & (trial_step >= config.trial_timeout)


def task_arrays(config: Config, dtype=jnp.float32):
    """Per-task start poses, targets and theoretical maxima as arrays with a task axis."""
    start = jnp.asarray([t.start for t in config.tasks], dtype)
    heading = jnp.asarray([math.radians(t.heading_deg) for t in config.tasks], dtype)
    target = jnp.asarray([t.target for t in config.tasks], dtype)
    best = jnp.asarray(config.theoretical_max(), dtype)
    return Pose(start, heading), target, best
