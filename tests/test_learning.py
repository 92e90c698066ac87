"""The learning rules on hand-computed numbers: traces (with the ended flag), row updates, row picks."""

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.agent.learning import accumulate, ascend_row, pick_row


def test_accumulate_by_hand():
    trace, phi = jnp.array([1.0, 2.0]), jnp.array([0.5, -1.0])
    # gamma * lambda = 0.45
    np.testing.assert_allclose(accumulate(trace, phi, 0.9, 0.5, True), [0.95, -0.1], rtol=1e-6)
    np.testing.assert_array_equal(accumulate(trace, phi, 0.9, 0.5, False), trace)
    # an ended trace is read as 0: learning starts it afresh, not learning leaves 0
    np.testing.assert_array_equal(accumulate(trace, phi, 0.9, 0.5, True, True), phi)
    np.testing.assert_array_equal(accumulate(trace, phi, 0.9, 0.5, False, True), [0.0, 0.0])


def test_accumulate_vmapped_over_lanes_with_mixed_flags():
    traces = jax.random.normal(jax.random.key(0), (4, 3, 5))
    phis = jax.random.normal(jax.random.key(1), (4, 3, 5))
    learn = jnp.array([True, False, True, False])
    ended = jnp.array([False, False, True, True])
    got = jax.vmap(accumulate, (0, 0, None, None, 0, 0))(traces, phis, 0.99, 0.9, learn, ended)
    for lane in range(4):
        live = np.zeros((3, 5)) if ended[lane] else np.asarray(traces[lane])
        want = 0.99 * 0.9 * live + np.asarray(phis[lane]) if learn[lane] else live
        np.testing.assert_allclose(got[lane], want, rtol=1e-6, atol=1e-7)


def test_ascend_row_changes_only_that_row():
    weights = jax.random.normal(jax.random.key(2), (3, 2, 4))
    trace = jax.random.normal(jax.random.key(3), (2, 4))
    row = jax.nn.one_hot(1, 3)
    got = ascend_row(weights, row, trace, 0.5, 0.1)
    np.testing.assert_array_equal(got[0], weights[0])
    np.testing.assert_array_equal(got[2], weights[2])
    np.testing.assert_allclose(got[1], weights[1] + 0.05 * trace, rtol=1e-6)


def test_pick_row_is_the_row_bit_for_bit():
    matrix = jax.random.normal(jax.random.key(4), (3, 2, 37))
    for k in range(3):
        np.testing.assert_array_equal(pick_row(matrix, k), matrix[k])
    picked = jax.vmap(pick_row)(jnp.stack([matrix] * 3), jnp.arange(3))
    np.testing.assert_array_equal(picked, matrix)


def test_after_choice_is_the_flag_itself():
    import jax.numpy as jnp

    from imrl_jax.agent.learning import after_choice

    for flag in (True, False):
        for k in range(3):
            assert bool(after_choice(jnp.bool_(flag), jnp.int32(k))) is flag
