"""The decoder a run starts from, decided in one place: its `decoder_from` (a run, a synergy
file or a shipped name), a prior's start (priors.py), or the Trainer's random one; each
task's own synergies beside it (`own_synergies`: what the task's own reward prior holds
outside the shared start); and the decoder a run's movement is measured from (the loop logs
it as decoder/change, ...)."""

from __future__ import annotations

import functools

import jax
import numpy as np

from discosyn_jax import config as config_lib
from discosyn_jax.agent import networks
from discosyn_jax.synergies import fitting, priors


def starting_decoder(trainer) -> dict | None:
  """The decoder a fresh run starts from (the one place that decides it): its
  `decoder_from`, a prior's start (priors.py, computed once per trainer), or None (the
  Trainer's random one)."""
  config = trainer.config
  if config.decoder_init in config_lib.PRIORS:
    return _prior_start(trainer)
  return fitting.load_decoder(config.decoder_from, config) if config.decoder_from else None


def starting_own(trainer, decoder: dict | None = None) -> np.ndarray | None:
  """(tasks, k, actions): each task's own synergies a fresh run starts from, None without
  them. Task n's are the top k directions of its own reward metric (priors.metric) outside
  the shared start's span (`decoder`, the start `starting_decoder` gave; None: the random
  one; an mlp decoder's span is not a subspace, so nothing is projected out), each as long
  as a shared direction on average (the shared kernel's mean singular value), so that an
  own activation moves the hand as far as a shared one."""
  config = trainer.config
  if not config.own_synergies:
    return None
  metrics = _reward_metrics(trainer)
  shared = np.zeros((trainer.action_size, 0))
  length = float(np.sqrt(trainer.action_size / config.n_synergies))  # lecun normal's
  if config.kind.linear:
    kernel = (decoder if decoder is not None else
              networks.random_decoder(config, trainer.action_size))["synergies"]["kernel"]
    shared = np.asarray(kernel, np.float64).T
    length = float(np.linalg.svd(shared, compute_uv=False).mean())
  own = priors.own(metrics, shared, config.own_synergies)
  return (length * own.transpose(0, 2, 1)).astype(np.float32)


@functools.lru_cache(maxsize=2)
def _reward_metrics(trainer) -> tuple[np.ndarray, ...]:
  """Each task's reward metric, measured once per trainer (the reward prior and the own
  synergies read the same)."""
  return tuple(priors.metric(env, "reward") for env in trainer.envs)


@functools.lru_cache(maxsize=2)
def _prior_start(trainer) -> dict | None:
  config = trainer.config
  if config.n_synergies >= trainer.action_size:  # W spans every action: nothing to choose
    return None
  response, pooling = config_lib.PRIORS[config.decoder_init]
  metrics = (_reward_metrics(trainer) if response == "reward" else
             [priors.metric(env, response) for env in trainer.envs])
  prior = priors.pool(list(metrics), config.n_synergies, pooling)
  return priors.start(networks.random_decoder(config, trainer.action_size), prior)


def decoder_reference(trainer, state, log=print):
  """The parameters whose decoder a run's movement is measured from: its initial decoder
  (for a frozen one, the decoder itself). None without a decoder, or when a fine-tuned
  decoder's source is gone."""
  config = trainer.config
  if trainer.decoder_drift is None:
    return None
  if config.freeze_decoder:
    return jax.tree.map(lambda x: x.copy(), state.params)  # train_step donates the state
  try:
    decoder = starting_decoder(trainer)
    return trainer.initial_params(decoder_params=decoder, own=starting_own(trainer, decoder))
  except ValueError as e:
    log(f"no decoder movement in the logs: {e}")
    return None
