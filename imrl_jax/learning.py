"""The learning rules of section 2 and MODEL.md "Learning": TD surprise, actor-critic updates, traces.

Each rule is w += eta * delta * e, where e is the network's eligibility trace
(e <- gamma * lambda * e + phi on the steps at which it learns; lambda = 0 gives the
paper's one-step rules exactly). It is written as one SGD step of optax on the
pseudo-gradient -delta * e.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import optax


def td_error(reward, value, next_value, gamma, terminal):
    """Surprise r + gamma V(x_t) - V(x_{t-1}); a terminal transition does not bootstrap."""
    return reward + gamma * jnp.where(terminal, 0.0, next_value) - value


def actor_features(action, output, xb):
    """phi of an expert actor: ((a - o) * o * (1 - o)) outer x~ (moves o towards the action)."""
    return ((action - output) * output * (1.0 - output))[:, None] * xb[None, :]


def selector_features(k, selection, xb):
    """phi of the selector actor: ((e_k - s) * s * (1 - s)) outer x~."""
    e = jax.nn.one_hot(k, selection.shape[0], dtype=selection.dtype)
    return ((e - selection) * selection * (1.0 - selection))[:, None] * xb[None, :]


def accumulate(trace, phi, gamma, trace_lambda, learn, ended=False):
    """e <- gamma * lambda * e + phi where the network learns this step; unchanged elsewhere.

    A trace that ``ended`` (at the previous step) is read as 0 first.
    """
    # Factors instead of jnp.where: XLA's CPU backend vectorises a multiply of a whole
    # array by each lane's scalar, but not a select on each lane's flag (about 2x
    # faster on the selector's trace). The same numbers, since traces are finite.
    # (1 - ended rather than a select between two literals, whose type Triton's lowering
    # loses: the GPU kernel uses this function too.)
    keep = jnp.where(learn, gamma * trace_lambda, 1.0) * (1.0 - jnp.asarray(ended, trace.dtype))
    return trace * keep + phi * jnp.asarray(learn, trace.dtype)


def ascend(weights, trace, delta, eta):
    """w += eta * delta * e, as an SGD step on the pseudo-gradient -delta * e."""
    sgd = optax.sgd(eta)
    updates, _ = sgd.update(-delta * trace, sgd.init(weights))
    return optax.apply_updates(weights, updates)


def ascend_row(weights, row, trace, delta, eta):
    """w[k] += eta * delta * e for the row k that the one-hot vector ``row`` picks; other rows unchanged."""
    sgd = optax.sgd(eta)
    updates, _ = sgd.update(-delta * trace, sgd.init(trace))
    # A product with the one-hot instead of a row write: under vmap a row write is a
    # scatter, a slow loop on XLA's CPU backend, and this is one vectorised pass. The
    # same numbers while the weights are finite (the other rows get + 0).
    return weights + row.reshape(row.shape + (1,) * trace.ndim) * updates


def pick_row(matrix, k):
    """matrix[k], as the sum of its rows times a one-hot vector (see :func:`ascend_row`).

    Under vmap a vectorised pass instead of a gather; the same numbers while the other
    rows are finite.
    """
    onehot = jax.nn.one_hot(k, matrix.shape[0], dtype=matrix.dtype)
    picked = onehot[0] * matrix[0]
    for j in range(1, matrix.shape[0]):
        picked = picked + onehot[j] * matrix[j]
    return picked
