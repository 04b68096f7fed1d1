"""Is a synergy space discovered, i.e. determined by the task set rather than by the seed?
The subspaces of runs' decoders, at their start and at their end, and the overlaps between
them (diagnostics.overlap: 1 the same subspace, chance max(p, q) / n).

A run's synergy basis is that of its decoder (diagnostics.synergy_basis: W, or an MLP's
Jacobian at z = 0). Its start is rebuilt from its config alone, as the Trainer draws it
(networks.random_decoder), or read from its `decoder_from`.
"""

from __future__ import annotations

import itertools
import pathlib

import numpy as np

from discosyn_jax.agent import networks
from discosyn_jax.config import PRIORS, TrainConfig
from discosyn_jax.synergies import diagnostics, fitting


def learned_basis(run_dir: pathlib.Path) -> np.ndarray | None:
  """The synergy basis of a run's newest checkpoint; None without one (logs kept alone)."""
  try:
    meta, params = fitting.read(run_dir)
  except ValueError:
    return None
  return fitting.basis(meta, params)


def initial_basis(config: TrainConfig, action_size: int) -> np.ndarray | None:
  """The synergy basis a run of `config` (on envs of `action_size` actions) starts from; None
  when its decoder_from is gone, or for a start from a prior (the same subspace
  for every seed, by construction)."""
  if config.decoder_init in PRIORS:  # the prior needs the envs; every seed starts in it
    return None
  if config.decoder_from:
    try:
      params = fitting.load_decoder(config.decoder_from, config)
    except ValueError:
      return None
  else:
    params = networks.random_decoder(config, action_size)
  return fitting.basis(fitting.architecture(config.to_dict()), params)


def cross_seed(bases: list[np.ndarray]) -> list[float]:
  """The overlap of every pair of bases (seeds)."""
  return [float(diagnostics.overlap(a, b)) for a, b in itertools.combinations(bases, 2)]
