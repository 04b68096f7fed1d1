"""Small shared pieces of the tests."""

import jax

from discosyn_jax.rollouts import run_episode  # noqa: F401  (the tests' episodes)


def uniform_policy(t, key, batch):
  return jax.random.uniform(key, (batch, 20), minval=-1.0, maxval=1.0)
