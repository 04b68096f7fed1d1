"""Whole batched episodes in one jitted call: the shape tests and calibration scripts share."""

from __future__ import annotations

import jax
import jax.numpy as jnp


def run_episode(env, keys, policy, steps=None, seed: int = 7):
  """Reset a batch of envs and run `steps` control steps (default: one episode).

  policy(t, key, batch) -> (batch, action size) actions. Returns (the reset state, the per-step
  states stacked along a leading time axis); no auto-reset: a terminated env keeps stepping.
  """
  return episode_fn(env, policy, steps, seed)(keys)


def episode_fn(env, policy, steps=None, seed: int = 7):
  """`run_episode` as a jitted function of the reset keys (to compile apart: `discosyn demo`)."""
  steps = steps or env.episode_length

  @jax.jit
  def go(keys):
    state = jax.vmap(env.reset)(keys)

    def body(carry, t):
      state, key = carry
      key, sub = jax.random.split(key)
      state = jax.vmap(env.step)(state, policy(t, sub, keys.shape[0]))
      return (state, key), state

    _, states = jax.lax.scan(body, (state, jax.random.PRNGKey(seed)), jnp.arange(steps))
    return state, states

  return go
