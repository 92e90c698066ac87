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


def _red_distance_sq(config: Config, x: jnp.ndarray, y: jnp.ndarray) -> jnp.ndarray:
    """Squared distance from points (x, y) to the nearest red edge on the nearest red line."""
    a = config.edge_length
    h = config.hex_apothem
    ox, oy = config.tiling_origin
    # Horizontal edges lie on the lines y = oy + m*h; on line m they are segments of
    # length a centred every 3a, shifted by 1.5a per line.  Lines are 2h/sqrt(3) > 30 cm
    # apart, so for a point within a line width only its nearest line matters.
    # floor and multiplications by constants vectorise on CPU; round, mod and / did not.
    y = y - oy
    m = jnp.floor(y * (1.0 / h) + 0.5)
    dy = y - m * h
    u = x - ox - 1.5 * a * m
    u = u - 3.0 * a * jnp.floor(u * (1.0 / (3.0 * a))) - 1.5 * a
    dx = jnp.maximum(jnp.abs(u) - 0.5 * a, 0.0)
    return dx * dx + dy * dy


def _colour_distances_sq(config: Config, p: jnp.ndarray) -> tuple[jnp.ndarray, ...]:
    """Squared distances from points (..., 2) to the nearest red, green and blue edge.

    Colour k's edges are the red ones turned by k*60 deg about a hexagon centre. Exact
    where the distance is below half the spacing of parallel lines (about 17 cm), which
    is all that colour decisions use.
    """
    ox, oy = config.tiling_origin
    qx, qy = p[..., 0] - ox, p[..., 1] - oy
    dists = []
    for k in range(3):
        c, s = math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)
        dists.append(_red_distance_sq(config, c * qx + s * qy + ox, -s * qx + c * qy + oy))
    return tuple(dists)


def colour_distances(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Distances (..., 3) from points (..., 2) to the nearest red, green and blue edge."""
    return jnp.sqrt(jnp.stack(_colour_distances_sq(config, p), -1))


def receptors(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Binary (R, G, B) receptors (..., 3) at points (..., 2): the one-hot floor colour.

    A point is on an edge within ``line_half_width``; the nearest edge wins and an exact
    tie (within ``colour_tie_tolerance``) goes to red, then green, then blue. Points
    outside the arena see no colour.
    """
    red, green, blue = _colour_distances_sq(config, p)
    nearest = jnp.minimum(jnp.minimum(red, green), blue)
    # One square root per point: d <= d_min + tol  <=>  d^2 <= (d_min + tol)^2.
    tie = jnp.square(jnp.sqrt(nearest) + config.colour_tie_tolerance)
    is_red, is_green, is_blue = red <= tie, green <= tie, blue <= tie
    size = config.arena_size
    inside = (p[..., 0] >= 0.0) & (p[..., 0] <= size) & (p[..., 1] >= 0.0) & (p[..., 1] <= size)
    on_line = (nearest <= config.line_half_width ** 2) & inside
    one_hot = [on_line & is_red, on_line & is_green & ~is_red, on_line & is_blue & ~is_red & ~is_green]
    return jnp.stack(one_hot, -1).astype(p.dtype)


def floor_colour(config: Config, p: jnp.ndarray) -> jnp.ndarray:
    """Colour index of the floor at points (..., 2): RED 0, GREEN 1, BLUE 2 or NONE -1."""
    one_hot = receptors(config, p)
    return jnp.where(jnp.any(one_hot > 0, -1), jnp.argmax(one_hot, -1), NONE).astype(jnp.int32)


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
