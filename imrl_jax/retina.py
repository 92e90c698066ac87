"""The retina of section 2 and MODEL.md "Retina": 6 x 2 points with binary R, G, B receptors."""

from __future__ import annotations

import jax.numpy as jnp

from imrl_jax.arena import Pose, floor_colour_xy
from imrl_jax.config import Config


def facing(pose: Pose) -> jnp.ndarray:
    """(cos, sin) of the heading: the unit vector the robot faces."""
    return jnp.stack([jnp.cos(pose.heading), jnp.sin(pose.heading)])


def sample_xy(config: Config, pose: Pose, direction: jnp.ndarray | None = None):
    """World coordinates x, y (forward rows, lateral points) of the retina's sample points.

    ``direction`` is :func:`facing` of the pose when the caller already has it: a lifetime
    carries it so that XLA cannot fuse cos and sin into every sample point's kernel.
    """
    dtype = pose.pos.dtype
    f = jnp.asarray(config.retina_forward, dtype)[:, None]
    lat = jnp.asarray(config.retina_lateral, dtype)[None, :]
    c, s = facing(pose) if direction is None else direction
    # forward along (c, s); positive lateral offsets to the robot's left, (-s, c)
    x = pose.pos[0] + f * c - lat * s
    y = pose.pos[1] + f * s + lat * c
    return x, y


def sample_points(config: Config, pose: Pose) -> jnp.ndarray:
    """World positions (forward rows, lateral points, 2) of the retina's sample points."""
    return jnp.stack(sample_xy(config, pose), -1)


def observe(config: Config, pose: Pose, direction: jnp.ndarray | None = None) -> jnp.ndarray:
    """The 36-value input x: [forward row][lateral point][R, G, B], 1 where that colour is seen."""
    colour = floor_colour_xy(config, *sample_xy(config, pose, direction))
    one_hot = colour[..., None] == jnp.arange(3)
    return one_hot.reshape(-1).astype(pose.pos.dtype)
