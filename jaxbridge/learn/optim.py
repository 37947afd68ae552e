"""The learner's optimiser: global-norm gradient clipping, then Adam (the paper's and the authors' code's).

The arithmetic and the state are optax's `chain(clip_by_global_norm(c), adam(lr))`, operation for
operation, except that each division of a tensor by a scalar is made elementwise: left as
`tensor / scalar`, XLA may turn it into a multiplication by the reciprocal in some programs and not in
others, and a seed's last bits then depended on the device count (docs/DESIGN.md, "Seeds over devices").
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import optax

B1, B2, EPS = 0.9, 0.999, 1e-8  # Adam's defaults (optax's, PyTorch's)


def _divide(tensor: jax.Array, scalar: jax.Array) -> jax.Array:
    """tensor / scalar as an elementwise division: the barrier hides the broadcast from the simplifier."""
    divisor = jax.lax.optimization_barrier(jnp.broadcast_to(scalar.astype(tensor.dtype), tensor.shape))
    return tensor / divisor


def clipped_adam(max_norm: float | None = None, learning_rate: float | None = None
                 ) -> optax.GradientTransformationExtraArgs:
    """Clip, then Adam. Built once: `max_norm` and `learning_rate` left None are given to each `update` as
    keyword arguments (the cycle's hyperparameter leaves), so one transformation serves every setting."""
    reference = optax.chain(optax.clip_by_global_norm(1.0), optax.adam(1.0))  # the state's layout only

    def update(grads, state, params=None, *, max_norm=max_norm, learning_rate=learning_rate):
        del params
        clip_state, (adam, scale_state) = state
        # Clip: rescale the whole gradient to norm max_norm when it is longer.
        norm = optax.tree.norm(grads)
        short = norm < max_norm
        grads = jax.tree.map(lambda g: jax.lax.select(short, g, _divide(g, norm) * max_norm), grads)
        # Adam: moving moments, bias-corrected, then a step of -learning_rate. `g ** 1`, `v + 0.0` and
        # `-1 * learning_rate` are optax's own expressions (order 1, eps_root 0, flip_sign), kept so
        # that XLA sees the same program and the numbers match it to the bit.
        mu = jax.tree.map(lambda g, m: (1 - B1) * (g ** 1) + B1 * m, grads, adam.mu)
        nu = jax.tree.map(lambda g, v: (1 - B2) * (g ** 2) + B2 * v, grads, adam.nu)
        count = optax.safe_increment(adam.count)
        mu_hat = jax.tree.map(lambda m: _divide(m, 1 - B1 ** count), mu)
        nu_hat = jax.tree.map(lambda v: _divide(v, 1 - B2 ** count), nu)
        step = jax.tree.map(lambda m, v: (-1 * learning_rate) * (m / (jnp.sqrt(v + 0.0) + EPS)), mu_hat, nu_hat)
        return step, (clip_state, (adam._replace(count=count, mu=mu, nu=nu), scale_state))

    return optax.GradientTransformationExtraArgs(reference.init, update)
