"""The policy's one chain, written once: obs -> head n -> z -> decoder (+ task n's posture,
where there is one) -> a, with
log pi(z, a | s, n) = log pi(z | s, n) + log p(a | z) (a decoder without noise, the
sequential baselines' fixed spaces, adds no log p(a | z)). With a residual (residual.py)
the action adds rho r, r from task n's residual head, and p(a | z) becomes the decoder's
Gaussian with r integrated out. Acting (trainer.py, evaluation.py) and the PPO loss (ppo.py)
both go through it."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from discosyn_jax.agent.networks import DiscoSyn, gaussian_log_prob

RESIDUAL_STREAM = 2  # r's draws: folded in apart from z's and a's, which stay a plain run's


def noise(key, batch: int, n_synergies: int, action_size: int, residual: bool = False):
  """The standard normal draws behind z and a (and r, with a residual), drawn apart from the
  networks so that a rollout split over devices uses the numbers one device would."""
  z_key, a_key = jax.random.split(key)
  draws = (jax.random.normal(z_key, (batch, n_synergies)),
           jax.random.normal(a_key, (batch, action_size)))
  if residual:
    r_key = jax.random.fold_in(key, RESIDUAL_STREAM)
    draws += (jax.random.normal(r_key, (batch, action_size)),)
  return draws


def sample(model: DiscoSyn, params, task: int, obs, draws, rho=None):
  """(z, a, log pi(z, a | s)) for normalised `obs` and the `noise` draws; `rho`: the
  residual's weight, with a residual."""
  z_noise, a_noise, *r_noise = draws
  z_mean, z_log_std = model.apply(params, task, obs, method=DiscoSyn.policy)
  z = z_mean + jnp.exp(z_log_std) * z_noise
  a_mean, a_log_std = model.apply(params, task, z, method=DiscoSyn.act)
  a = a_mean if a_log_std is None else a_mean + jnp.exp(a_log_std) * a_noise
  if model.residual:
    r_mean, r_log_std = model.apply(params, task, obs, method=DiscoSyn.residual_policy)
    a = a + rho * (r_mean + jnp.exp(r_log_std) * r_noise[0])
    a_mean, a_log_std = _without_r(a_mean, a_log_std, rho, r_mean, r_log_std)
  return z, a, _log_prob(z, z_mean, z_log_std, a, a_mean, a_log_std)


def deterministic(model: DiscoSyn, params, task: int, obs, rho=None):
  """(z, a): the head's mean and the decoder's mean of it (plus rho times the residual's
  mean, with a residual)."""
  z_mean, _ = model.apply(params, task, obs, method=DiscoSyn.policy)
  a = model.apply(params, task, z_mean, method=DiscoSyn.act)[0]
  if model.residual:
    a = a + rho * model.apply(params, task, obs, method=DiscoSyn.residual_policy)[0]
  return z_mean, a


def log_prob(model: DiscoSyn, params, task: int, obs, z, action, rho=None):
  """log pi(z, a | s) of given samples, and the log stds of z and of the decoder's own noise
  (for the entropies)."""
  z_mean, z_log_std = model.apply(params, task, obs, method=DiscoSyn.policy)
  a_mean, decoder_log_std = model.apply(params, task, z, method=DiscoSyn.act)
  a_log_std = decoder_log_std
  if model.residual:
    r_mean, r_log_std = model.apply(params, task, obs, method=DiscoSyn.residual_policy)
    a_mean, a_log_std = _without_r(a_mean, a_log_std, rho, r_mean, r_log_std)
  return _log_prob(z, z_mean, z_log_std, action, a_mean, a_log_std), z_log_std, decoder_log_std


def action_parts(model: DiscoSyn, params, task: int, obs, z, rho):
  """(the synergies' part of the action, the residual's) at given samples: the decoder's
  mean (task posture included) and rho times the residual's mean."""
  synergy = model.apply(params, task, z, method=DiscoSyn.act)[0]
  return synergy, rho * model.apply(params, task, obs, method=DiscoSyn.residual_policy)[0]


def _without_r(a_mean, a_log_std, rho, r_mean, r_log_std):
  """p(a | z, s) with r integrated out: a = decoder mean + rho r + decoder noise, a sum of
  independent Gaussians (residual.py: why the marginal, not r's own draw)."""
  variance = jnp.exp(2 * a_log_std) + (rho * jnp.exp(r_log_std)) ** 2
  return a_mean + rho * r_mean, 0.5 * jnp.log(variance)


def _log_prob(z, z_mean, z_log_std, a, a_mean, a_log_std):
  out = gaussian_log_prob(z, z_mean, z_log_std)
  return out if a_log_std is None else out + gaussian_log_prob(a, a_mean, a_log_std)
