"""The arena of section 2 and MODEL.md "Arena and floor", "Robot": floor colours, walls, moves.

The floor is a flat-top hexagonal tiling whose edges are coloured by direction (0 deg red,
60 deg green, 120 deg blue). Every colour family is the red family turned by a multiple of
60 deg about a hexagon centre, so one closed-form distance to the nearest red edge, applied
to the point turned back, gives the distance to every colour.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

from imrl_jax.config import Config

RED, GREEN, BLUE, NONE = 0, 1, 2, -1


class Pose(NamedTuple):
    """Robot centre (x, y) in cm and heading in radians."""

    pos: jnp.ndarray  # (2,)
    heading: jnp.ndarray  # ()


def _red_distance_sq(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Squared distance from points ``p`` (..., 2) to the nearest red edge on the nearest red line."""
    a = config.edge_length
    h = config.hex_apothem
    ox, oy = config.tiling_origin
    # Horizontal edges lie on the lines y = oy + m*h; on line m they are segments of
    # length a centred every 3a, shifted by 1.5a per line.  Lines are 2h/sqrt(3) > 30 cm
    # apart, so for a point within a line width only its nearest line matters.
    m = jnp.round((p[..., 1] - oy) / h)
    dy = p[..., 1] - oy - m * h
    u = p[..., 0] - ox - 1.5 * a - 1.5 * a * m
    u = jnp.mod(u + 1.5 * a, 3.0 * a) - 1.5 * a
    dx = jnp.maximum(jnp.abs(u) - 0.5 * a, 0.0)
    return dx * dx + dy * dy


def colour_distances(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Distances (..., 3) from points (..., 2) to the nearest red, green and blue edge.

    Exact where the distance is below half the spacing of parallel lines (about 17 cm),
    which is all that colour decisions use.
    """
    o = jnp.asarray(config.tiling_origin, dtype=p.dtype)
    q = p - o
    dists = []
    for k in range(3):  # colour k's edges are the red ones turned by k*60 deg
        c, s = math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)
        back = jnp.stack([c * q[..., 0] + s * q[..., 1], -s * q[..., 0] + c * q[..., 1]], -1)
        dists.append(_red_distance_sq(config, back + o))
    return jnp.sqrt(jnp.stack(dists, -1))


def floor_colour(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Colour index of the floor at points (..., 2): RED 0, GREEN 1, BLUE 2 or NONE -1.

    A point is on an edge within ``line_half_width``; the nearest edge wins and an exact
    tie (within ``colour_tie_tolerance``) goes to red, then green, then blue. Points
    outside the arena see no colour.
    """
    d = colour_distances(config, p)
    d_min = jnp.min(d, axis=-1, keepdims=True)
    # argmax returns the first True: the tie order red, green, blue.
    colour = jnp.argmax(d <= d_min + config.colour_tie_tolerance, axis=-1).astype(jnp.int32)
    inside = jnp.all((p >= 0.0) & (p <= config.arena_size), axis=-1)
    on_line = (d_min[..., 0] <= config.line_half_width) & inside
    return jnp.where(on_line, colour, NONE)


def move(config: Config, pose: Pose, action: jnp.ndarray) -> Pose:
    """Turn by (a0 - 0.5) * 2 * max_turn, then advance max_speed * a1, then clamp to the walls."""
    turn = (action[0] - 0.5) * 2.0 * math.radians(config.max_turn_deg)
    # Keeping the heading in [0, 2pi) keeps float32 precise over 150,000 steps of turning.
    heading = jnp.mod(pose.heading + turn, 2.0 * math.pi)
    step = config.max_speed * action[1]
    pos = pose.pos + step * jnp.stack([jnp.cos(heading), jnp.sin(heading)])
    r = config.robot_radius
    pos = jnp.clip(pos, r, config.arena_size - r)
    return Pose(pos, heading)


def task_arrays(config: Config, dtype=jnp.float32):
    """Per-task start poses, targets and theoretical maxima as arrays with a task axis."""
    start = jnp.asarray([t.start for t in config.tasks], dtype)
    heading = jnp.asarray([math.radians(t.heading_deg) for t in config.tasks], dtype)
    target = jnp.asarray([t.target for t in config.tasks], dtype)
    best = jnp.asarray(config.theoretical_max(), dtype)
    return Pose(start, heading), target, best
