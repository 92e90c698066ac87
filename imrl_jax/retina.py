"""The retina of section 2 and MODEL.md "Retina": 6 x 2 points with binary R, G, B receptors."""

from __future__ import annotations

import jax.numpy as jnp

from imrl_jax.arena import Pose, floor_colour
from imrl_jax.config import Config


def sample_points(config: Config, pose: Pose) -> jnp.ndarray:
    """World positions (forward rows, lateral points, 2) of the retina's sample points."""
    dtype = pose.pos.dtype
    f = jnp.asarray(config.retina_forward, dtype)[:, None]
    lat = jnp.asarray(config.retina_lateral, dtype)[None, :]
    c, s = jnp.cos(pose.heading), jnp.sin(pose.heading)
    # forward along (c, s); positive lateral offsets to the robot's left, (-s, c)
    x = pose.pos[0] + f * c - lat * s
    y = pose.pos[1] + f * s + lat * c
    return jnp.stack([x, y], -1)


def observe(config: Config, pose: Pose) -> jnp.ndarray:
    """The 36-value input x: [forward row][lateral point][R, G, B], 1 where that colour is seen."""
    colour = floor_colour(config, sample_points(config, pose))
    one_hot = colour[..., None] == jnp.arange(3)
    return one_hot.reshape(-1).astype(pose.pos.dtype)
