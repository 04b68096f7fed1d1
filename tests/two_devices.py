"""Run in its own process (XLA reads the device count at backend start-up): the train step
on a mesh of 2 CPU devices against the same step on 1 device.

  XLA_FLAGS=--xla_force_host_platform_device_count=2 python -m tests.two_devices

Prints one JSON line: the largest parameter difference after a few steps of the toy task,
the evaluation after one step on valve1 with the native backend, and the env batches the native
host callback received on each layout.
"""

import json

import jax
import numpy as np

from discosyn_jax import assemble, tasks
from discosyn_jax.config import TrainConfig
from discosyn_jax.training.trainer import Trainer
from tests.test_trainer import two_task_trainer


def params_after(trainer: Trainer, steps: int, evaluate: bool = False):
  state = trainer.init()
  step = trainer.train_step.lower(state).compile()  # as the loop does: layouts must hold
  for _ in range(steps):
    state, metrics = step(state)
  results = None
  if evaluate:  # not split: the callbacks of the evaluation run on one device
    results = trainer.returns(state.params, state.normalizers, jax.random.PRNGKey(1))
  return jax.device_get(state.params), float(metrics["loss"]), jax.device_get(results)


def max_difference(a, b) -> float:
  return max(float(np.abs(x - y).max()) for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)))


def native_batches(trainer: Trainer) -> list[int]:
  """Record the batch of every host step call (the callback is installed before tracing)."""
  seen = []
  physics = trainer.envs[0].physics
  host_step = physics._host_step

  def recording(raw, ctrl):
    seen.append(int(np.prod(raw.shape[:-1])))
    return host_step(raw, ctrl)

  physics._host_step = recording
  return seen


def main():
  assert jax.device_count() == 2, jax.devices()
  out = {}
  small = dict(policy_hidden=(16,), value_hidden=(16,), discriminator_hidden=(16,),
               num_envs=8, unroll_length=4, num_minibatches=2, update_epochs=2, squash_z=False,
               decoder_init="random")
  toy = [params_after(two_task_trainer(devices=n, **small), steps=3) for n in (1, 2)]
  out["toy_max_param_diff"] = max_difference(toy[0][0], toy[1][0])
  out["toy_losses"] = [toy[0][1], toy[1][1]]

  config = TrainConfig(tasks=("valve1",), n_synergies=2, backend="native",
                       eval_envs=3,
                       **{**small, "num_envs": 4, "unroll_length": 3, "update_epochs": 1})
  runs, batches = [], []
  for n in (1, 2):
    trainer = assemble.trainer(config, devices=n)
    batches.append(native_batches(trainer))
    runs.append(params_after(trainer, steps=1, evaluate=True))
  out["native_max_param_diff"] = max_difference(runs[0][0], runs[1][0])
  out["native_eval"] = [jax.tree.map(float, r[2]) for r in runs]
  out["native_callback_batches"] = [sorted(set(b)) for b in batches]
  try:
    assemble.trainer(config.replace(num_envs=5, unroll_length=4), devices=2)
  except ValueError as err:
    out["odd_batch_error"] = str(err)
  print(json.dumps(out))


if __name__ == "__main__":
  main()
