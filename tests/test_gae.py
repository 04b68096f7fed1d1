"""trainer.gae: brax's GAE fed the rollout's ends, on hand-computed trajectories and against
the definition written out in NumPy (tests/reference.py)."""

import numpy as np

from discosyn_jax.config import TrainConfig
from discosyn_jax.training.trainer import gae
from tests import reference


def column(*values):
  return np.array(values, np.float32)[:, None]  # (T, 1): one env


def test_termination_and_truncation_by_hand():
  """gamma 0.5, lambda 1: the episode terminates after step 1 and is cut by the time
  limit at step 3. Targets are the discounted returns within each episode; the truncated
  step is left out (advantage 0, target its own value) and step 2 bootstraps from it."""
  config = TrainConfig(squash_z=False, decoder_init="random", discount=0.5, gae_lambda=1.0)
  target, advantage = gae(reward=column(1, 2, 3, 4), value=column(10, 20, 30, 40),
                          bootstrap=np.array([50.0], np.float32), done=column(0, 1, 0, 1),
                          truncation=column(0, 0, 0, 1), config=config)
  np.testing.assert_allclose(target[:, 0], [1 + 0.5 * 2, 2, 3 + 0.5 * 40, 40])
  np.testing.assert_allclose(advantage[:, 0], [2 - 10, 2 - 20, 23 - 30, 0])


def test_lambda_zero_by_hand():
  """gamma 0.5, lambda 0, no ends: targets are one-step TD targets; brax's advantage is
  r_t + gamma target_{t+1} - v_t (not the TD error)."""
  config = TrainConfig(squash_z=False, decoder_init="random", discount=0.5, gae_lambda=0.0)
  zeros = column(0, 0, 0)
  target, advantage = gae(reward=column(1, 1, 1), value=column(2, 4, 6),
                          bootstrap=np.array([8.0], np.float32), done=zeros, truncation=zeros,
                          config=config)
  np.testing.assert_allclose(target[:, 0], [1 + 0.5 * 4, 1 + 0.5 * 6, 1 + 0.5 * 8])
  np.testing.assert_allclose(advantage[:, 0], [1 + 0.5 * 4 - 2, 1 + 0.5 * 5 - 4, 1 + 0.5 * 8 - 6])


def test_random_rollout_matches_the_definition():
  rng = np.random.default_rng(0)
  T, B = 9, 6
  done = (rng.random((T, B)) < 0.3).astype(np.float32)
  truncation = done * (rng.random((T, B)) < 0.5)
  assert 0 < truncation.sum() < done.sum()
  reward, value = rng.normal(size=(2, T, B)).astype(np.float32)
  bootstrap = rng.normal(size=B).astype(np.float32)
  config = TrainConfig(squash_z=False, decoder_init="random", discount=0.9, gae_lambda=0.8)
  got = gae(reward, value, bootstrap, done, truncation, config)
  want = reference.gae(reward, value, bootstrap, done * (1 - truncation), truncation, 0.9, 0.8)
  np.testing.assert_allclose(got[0], want[0], rtol=1e-5, atol=1e-5)
  np.testing.assert_allclose(got[1], want[1], rtol=1e-5, atol=1e-5)
