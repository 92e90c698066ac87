"""The retina of section 2 and MODEL.md "Retina": 6 x 2 points with binary R, G, B receptors."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from imrl_jax.world.arena import Pose, floor_colour_xy, heading_vector
from imrl_jax.config import Config


def sample_xy(config: Config, pose: Pose, direction=None) -> tuple[jnp.ndarray, jnp.ndarray]:
    """World coordinates x, y of the retina's sample points, forward row by forward row.

    ``direction`` is :func:`heading_vector` of the pose's heading, where the caller has it.
    """
    dtype = pose.pos.dtype
    f, lat = np.meshgrid(config.retina_forward, config.retina_lateral, indexing="ij")
    f, lat = jnp.asarray(f.ravel(), dtype), jnp.asarray(lat.ravel(), dtype)
    c, s = heading_vector(pose.heading) if direction is None else direction
    # forward along (c, s); positive lateral offsets to the robot's left, (-s, c).
    # Elementwise, XLA fuses this into each colour's distance kernel, which costs less
    # than a matrix product (a library call).
    return pose.pos[0] + f * c - lat * s, pose.pos[1] + f * s + lat * c


def sample_points(config: Config, pose: Pose) -> jnp.ndarray:
    """World positions (forward rows, lateral points, 2) of the retina's sample points."""
    rows, points = len(config.retina_forward), len(config.retina_lateral)
    return jnp.stack(sample_xy(config, pose), -1).reshape(rows, points, 2)


def observe(config: Config, pose: Pose, direction=None) -> jnp.ndarray:
    """The 36-value input x: [forward row][lateral point][R, G, B], 1 where that colour is seen.

    ``direction`` is :func:`heading_vector` of the pose's heading, where the caller has it.
    """
    dtype = pose.pos.dtype
    colour = floor_colour_xy(config, *sample_xy(config, pose, direction))
    # The colour as a float, 3 for none: exactly sqrt(0, 1, 4, 9). The square root is for
    # XLA, which fuses cheap operations into every kernel that reads them but not an
    # expensive one into a kernel that reads each value 3 times, as the one-hot does. So
    # each point's colour is decided once, in the kernel that computes its distances,
    # rather than 3 times per point in the one-hot's kernel (half the retina's time).
    squared = jnp.where(colour < 0, 9, colour * colour).astype(dtype)
    one_hot = jnp.sqrt(squared)[..., None] == jnp.arange(3, dtype=dtype)
    return one_hot.reshape(-1).astype(dtype)
