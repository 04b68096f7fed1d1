"""The decoder a run starts from, decided in one place: its `decoder_from` (a run, a synergy
file or a shipped name), a prior's start (priors.py), or the Trainer's random one; and the
decoder a run's movement is measured from (the loop logs it as decoder/change, ...)."""

from __future__ import annotations

import functools

import jax

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


@functools.lru_cache(maxsize=2)
def _prior_start(trainer) -> dict | None:
  config = trainer.config
  if config.n_synergies >= trainer.action_size:  # W spans every action: nothing to choose
    return None
  response, pooling = config_lib.PRIORS[config.decoder_init]
  prior = priors.basis(trainer.envs, config.n_synergies, response, pooling)
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
    return trainer.initial_params(decoder_params=starting_decoder(trainer))
  except ValueError as e:
    log(f"no decoder movement in the logs: {e}")
    return None
