"""Small shared pieces of the tests."""

import jax
import jax.numpy as jnp


def run_episode(env, keys, policy, steps=None):
  """Reset a batch of envs and run `steps` control steps; return the per-step states.

  policy(t, key, batch) -> (batch, 20) actions. One jit per call: reset and the scan.
  """
  steps = steps or env.episode_length

  @jax.jit
  def go(keys):
    state = jax.vmap(env.reset)(keys)

    def body(carry, t):
      state, key = carry
      key, sub = jax.random.split(key)
      state = jax.vmap(env.step)(state, policy(t, sub, keys.shape[0]))
      return (state, key), state

    _, states = jax.lax.scan(body, (state, jax.random.PRNGKey(7)), jnp.arange(steps))
    return state, states

  return go(keys)


def uniform_policy(t, key, batch):
  return jax.random.uniform(key, (batch, 20), minval=-1.0, maxval=1.0)
