"""The policy's one chain, written once: obs -> head n -> z -> decoder (+ task n's posture,
where there is one) -> a, with
log pi(z, a | s, n) = log pi(z | s, n) + log p(a | z) (a decoder without noise, the
sequential baselines' fixed spaces, adds no log p(a | z)). Acting (train.py, evaluation.py)
and the PPO loss (ppo.py) both go through it."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from discosyn_jax.agent.networks import DiscoSyn, gaussian_log_prob


def noise(key, batch: int, n_synergies: int, action_size: int):
  """The standard normal draws behind z and a, drawn apart from the networks so that a
  rollout split over devices uses the numbers one device would."""
  z_key, a_key = jax.random.split(key)
  return (jax.random.normal(z_key, (batch, n_synergies)),
          jax.random.normal(a_key, (batch, action_size)))


def sample(model: DiscoSyn, params, task: int, obs, draws):
  """(z, a, log pi(z, a | s)) for normalised `obs` and the `noise` draws."""
  z_noise, a_noise = draws
  z_mean, z_log_std = model.apply(params, task, obs, method=DiscoSyn.policy)
  z = z_mean + jnp.exp(z_log_std) * z_noise
  a_mean, a_log_std = model.apply(params, task, z, method=DiscoSyn.act)
  a = a_mean if a_log_std is None else a_mean + jnp.exp(a_log_std) * a_noise
  return z, a, _log_prob(z, z_mean, z_log_std, a, a_mean, a_log_std)


def deterministic(model: DiscoSyn, params, task: int, obs):
  """(z, a): the head's mean and the decoder's mean of it."""
  z_mean, _ = model.apply(params, task, obs, method=DiscoSyn.policy)
  return z_mean, model.apply(params, task, z_mean, method=DiscoSyn.act)[0]


def log_prob(model: DiscoSyn, params, task: int, obs, z, action):
  """log pi(z, a | s) of given samples, and the two log stds (for the entropies)."""
  z_mean, z_log_std = model.apply(params, task, obs, method=DiscoSyn.policy)
  a_mean, a_log_std = model.apply(params, task, z, method=DiscoSyn.act)
  return _log_prob(z, z_mean, z_log_std, action, a_mean, a_log_std), z_log_std, a_log_std


def _log_prob(z, z_mean, z_log_std, a, a_mean, a_log_std):
  out = gaussian_log_prob(z, z_mean, z_log_std)
  return out if a_log_std is None else out + gaussian_log_prob(a, a_mean, a_log_std)
