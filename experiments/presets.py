"""Named training configs: `discosyn train --preset NAME`; flags replace single fields.

Each preset is a TrainConfig (discosyn_jax/config.py), so a typo in a field name fails at
import, not in the middle of a run.
"""

from __future__ import annotations

from discosyn_jax.config import TrainConfig

SET1 = ("valve0", "valve1", "valve2", "valve3")

PRESETS: dict[str, TrainConfig] = {
    # CPU, a few minutes: the whole machinery on the four valves, far too short to solve them
    "quickstart": TrainConfig(tasks=SET1, n_synergies=3, decoder="linear", num_envs=16,
                              unroll_length=20, num_minibatches=4, update_epochs=2, steps=40,
                              eval_every=20, eval_envs=16, checkpoint_every=20),
    # the paper's set #1 with 3 linear synergies (Table I, DiscoSyn3-L)
    "set1-disco3-linear": TrainConfig(tasks=SET1, n_synergies=3, decoder="linear",
                                      num_envs=128, unroll_length=20, num_minibatches=8,
                                      update_epochs=4, steps=2000, eval_every=50,
                                      eval_envs=64, checkpoint_every=100),
    "set1-disco3-mlp": TrainConfig(tasks=SET1, n_synergies=3, decoder="mlp", num_envs=128,
                                   unroll_length=20, num_minibatches=8, update_epochs=4,
                                   steps=2000, eval_every=50, eval_envs=64,
                                   checkpoint_every=100),
    # independent full-action PPO on one valve (the paper's first baseline stage)
    "valve3-ppo": TrainConfig(tasks=("valve3",), decoder="identity", n_synergies=20, alpha2=0.0,
                              alpha3=0.0, init_z_std=0.5, num_envs=128, unroll_length=20,
                              num_minibatches=8, update_epochs=4, steps=2000, eval_every=50,
                              eval_envs=64, checkpoint_every=100),
}


def preset(name: str) -> TrainConfig:
  if name not in PRESETS:
    raise ValueError(f"unknown preset {name!r}; presets: {', '.join(PRESETS)}")
  return PRESETS[name]
