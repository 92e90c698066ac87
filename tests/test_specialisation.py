"""The specialisation measure (claim 7; docs/CHILDHOOD.md) on experts whose behaviour is known by construction."""

import jax.numpy as jnp
import numpy as np

from imrl_jax.analysis import behaviour as B
from imrl_jax.config import make_config
from imrl_jax.analysis.controllers import perceptron_followers
from imrl_jax.agent.networks import decode


def test_probe_starts_lie_on_their_colour_before_a_junction():
    config = make_config("paper", condition="EE-LS")
    starts = B.probe_starts(config, per_colour=4)
    colours = B.retina_colours(config, starts.pos[:, None, :], starts.heading[:, None])  # what the retina sees
    from imrl_jax.world.arena import floor_colour
    under = np.asarray(floor_colour(config, starts.pos))
    np.testing.assert_array_equal(under, np.repeat([0, 1, 2], 4))  # the robot stands on an edge of its colour
    # 20 cm ahead is a vertex: a point of all three colours' edges, so the retina (17-21 cm) sees two colours.
    assert colours.shape == (12, 1, 2, 6)


def test_colour_followers_follow_one_colour_each_and_a_straight_driver_none():
    config = make_config("paper", condition="EE-LS")
    followers = B.specialisation(config, decode(config, perceptron_followers(config).reshape(-1)), per_colour=4,
                                 num_steps=60)
    np.testing.assert_array_equal(followers.followed, [0, 1, 2])
    np.testing.assert_allclose(followers.takes, np.eye(3), atol=1e-9)
    assert followers.num_colours == 3
    assert np.all(followers.speed > 1.5)

    straight = B.specialisation(config, decode(config, jnp.zeros(config.num_genes)), per_colour=4, num_steps=60)
    np.testing.assert_array_equal(straight.followed, [-1, -1, -1])
    np.testing.assert_allclose(straight.speed, 1.0, atol=1e-4)  # sigmoid(0) of the top speed, 2 cm
    np.testing.assert_allclose(straight.turn, 0.0, atol=1e-4)
    assert straight.num_colours == 0
