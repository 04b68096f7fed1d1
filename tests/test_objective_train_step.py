"""What the train step feeds PPO, read back from a real (jitted) step on a tiny task whose
envs end at different steps, some by termination and some by the time limit, and
checked against NumPy: the reward (scaled, plus alpha2 log q(z|a)), the GAE targets and
advantages, the observation normaliser and the log-probs stored at sampling."""

import jax
import numpy as np
import pytest

from discosyn_jax.config import TrainConfig
from discosyn_jax.training.trainer import Trainer
from tests import reference
from tests.toy_env import StopOnSignal

TARGET = np.linspace(-0.8, 0.8, 20)
CONFIG = TrainConfig(squash_z=False, decoder_init="random", tasks=("a",), n_synergies=3, policy_hidden=(16, 16), value_hidden=(16, 16),
                     discriminator_hidden=(16, 16), num_envs=8, unroll_length=6,
                     num_minibatches=2, update_epochs=1, alpha2=0.3, reward_scaling=0.5,
                     discount=0.9, gae_lambda=0.8, learning_rate=1e-2)
STEPS = 3


@pytest.fixture(scope="module")
def steps():
  """[(state before, state after, what the step saw)] for STEPS train steps: `traj` the
  rollout, `last_obs` the observations after it, `samples` what the update optimised."""
  trainer = Trainer(CONFIG, envs=[StopOnSignal(TARGET, episode_length=4)])
  seen = {}
  unroll, update = trainer._unroll, trainer._update

  def spy_unroll(*args):
    env_state, traj = unroll(*args)
    seen.update(traj=traj, last_obs=env_state.obs)
    return env_state, traj

  def spy_update(params, opt_state, samples, key, *rest):  # rest: the residual's weight
    seen["samples"] = samples[0]
    return update(params, opt_state, samples, key, *rest)

  trainer._unroll, trainer._update = spy_unroll, spy_update
  # the spies' values are tracers of this very trace, so the jitted step can return them
  step = jax.jit(lambda state: (trainer._train_step(state)[0], dict(seen)))
  state, out = trainer.init(), []
  for _ in range(STEPS):
    new, saw = step(state)
    out.append(jax.device_get((state, new, saw)))
    state = new
  return out


def normalize(obs, norm):
  return np.clip((obs - norm.mean) / norm.std, -10, 10)


def test_the_rollouts_end_both_ways_at_different_steps(steps):
  done = np.concatenate([saw["traj"]["done"] for _, _, saw in steps])
  truncation = np.concatenate([saw["traj"]["truncation"] for _, _, saw in steps])
  assert 0 < truncation.sum() < done.sum()  # some terminations, some time limits
  ending = done.sum(axis=1)
  assert ((0 < ending) & (ending < CONFIG.num_envs)).any()  # some envs end, others go on


def test_normaliser_holds_every_observation_seen_and_the_update_uses_it(steps):
  seen_obs = []
  for before, after, saw in steps:
    obs = saw["traj"]["obs"]
    seen_obs.append(obs.reshape(-1, obs.shape[-1]))
    every = np.concatenate(seen_obs)
    norm = after.normalizers[0]
    np.testing.assert_allclose(norm.mean, every.mean(0), rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(norm.std, np.maximum(every.std(0), 1e-6), rtol=1e-4)  # brax: std >= 1e-6
    # the update sees this rollout normalised by the statistics that include it
    np.testing.assert_allclose(saw["samples"].obs, normalize(obs, norm).reshape(-1, obs.shape[-1]),
                               rtol=1e-5, atol=1e-5)


def test_stored_log_probs_are_the_policys_at_sampling(steps):
  """Ratio 1 before the update: the stored log pi(z|s) + log p(a|z) is the density of the
  sample under the params and the normaliser it was drawn with."""
  for before, _, saw in steps:
    traj = saw["traj"]
    p = reference.as_numpy(before.params["params"])
    obs = normalize(traj["obs"], before.normalizers[0])
    want = reference.joint_log_prob(p, "linear", 0, obs, traj["z"], traj["action"])
    np.testing.assert_allclose(np.exp(traj["log_prob"] - want), 1.0, atol=1e-4)


def test_gae_gets_the_scaled_reward_plus_alpha2_log_q_and_the_episode_ends(steps):
  for before, after, saw in steps:
    traj, samples = saw["traj"], saw["samples"]
    p = reference.as_numpy(before.params["params"])
    q_mean, q_log_std = reference.gaussian_head(p["discriminator"], traj["action"])
    log_q = reference.log_prob(traj["z"], q_mean, q_log_std)
    assert np.std(CONFIG.alpha2 * log_q) > 0.05  # the bonus weighs in
    reward = CONFIG.reward_scaling * traj["reward"] + CONFIG.alpha2 * log_q
    norm = after.normalizers[0]
    value = reference.value(p, 0, normalize(traj["obs"], norm))
    bootstrap = reference.value(p, 0, normalize(saw["last_obs"], norm))
    termination = traj["done"] * (1 - traj["truncation"])
    target, advantage = reference.gae(reward, value, bootstrap, termination, traj["truncation"],
                                      CONFIG.discount, CONFIG.gae_lambda)
    np.testing.assert_allclose(samples.target, target.reshape(-1), rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(samples.advantage, advantage.reshape(-1), rtol=1e-4, atol=1e-4)
