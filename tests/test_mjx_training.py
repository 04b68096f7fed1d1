"""The GPU path's training on the CPU: MJX under `Trainer.init` and one train step.

`init` once ran MJX op by op (minutes per reset); it must be one jitted function, so this
test, at 2 envs, takes about as long as compiling the step.
"""

import jax
import numpy as np

from discosyn_jax.config import TrainConfig
from discosyn_jax.train import Trainer


def test_mjx_trainer_inits_and_trains_one_step():
  config = TrainConfig(tasks=("valve0",), n_synergies=3, decoder="linear", num_envs=2,
                       unroll_length=2, num_minibatches=1, update_epochs=1, steps=1,
                       eval_every=0, eval_envs=2, checkpoint_every=0, backend="mjx")
  trainer = Trainer(config)
  assert trainer.envs[0].backend == "mjx"
  state = trainer.init()
  assert trainer._fresh_state._cache_size() == 1  # built by one compiled function
  assert state.env_states[0].obs.shape == (2, trainer.obs_sizes[0])
  before = jax.tree.map(np.asarray, state.params)
  state, metrics = trainer.train_step(state)
  assert int(state.step) == 1 and bool(metrics["finite"])
  moved = jax.tree.leaves(jax.tree.map(lambda a, b: np.abs(np.asarray(a) - b).max(),
                                       state.params, before))
  assert max(moved) > 0
