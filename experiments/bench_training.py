"""Benchmark: training env steps/s of a preset beside raw MuJoCo C on the same batch.

Prints, for the preset's train step (every task's rollout, GAE, PPO epochs, discriminator):
  compile s       lowering + compiling the jitted train step
  train env/s     env steps per second of whole train steps (best of --repeats timings of
                  --steps steps each, after one warm-up step)
  physics share   the fraction of train-step time spent inside the native physics callbacks
  rollout env/s   raw `mujoco.rollout` of the same models at the same batch (per task, for
                  unroll_length control steps each, as the train step does): the limit
  ratio           train env/s / rollout env/s

  python experiments/bench_training.py                          # set1-disco3-linear
  python experiments/bench_training.py --preset quickstart --num-envs 64
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import jax
import mujoco

from discosyn_jax.train import Trainer
from experiments import bench_physics, presets


class CallbackClock:
  """Wall time spent in the native backends' host callbacks (installed before tracing)."""

  def __init__(self, envs):
    self.seconds = 0.0
    for env in envs:
      for name in ("_host_step", "_host_init"):
        setattr(env.physics, name, self._timed(getattr(env.physics, name)))

  def _timed(self, fn):
    def run(*args):
      start = time.perf_counter()
      try:
        return fn(*args)
      finally:
        self.seconds += time.perf_counter() - start
    return run


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--preset", default="set1-disco3-linear")
  parser.add_argument("--num-envs", type=int, help="envs per task (default: the preset's)")
  parser.add_argument("--epochs", type=int, help="PPO epochs (default: the preset's)")
  parser.add_argument("--steps", type=int, default=5, help="train steps per timing")
  parser.add_argument("--repeats", type=int, default=2)
  args = parser.parse_args()
  config = presets.preset(args.preset).replace(backend="native")
  if args.num_envs:
    config = config.replace(num_envs=args.num_envs)
  if args.epochs:
    config = config.replace(update_epochs=args.epochs)
  config = config.validate()
  nthread = int(os.environ.get("DISCOSYN_NATIVE_THREADS", os.cpu_count() or 1))

  trainer = Trainer(config)
  clock = CallbackClock(trainer.envs)
  state = trainer.init()
  start = time.perf_counter()
  step = trainer.train_step.lower(state).compile()
  compile_s = time.perf_counter() - start
  state, metrics = step(state)
  jax.block_until_ready(metrics)

  best, share = float("inf"), float("nan")
  for _ in range(args.repeats):
    clock.seconds = 0.0
    start = time.perf_counter()
    for _ in range(args.steps):
      state, metrics = step(state)
    jax.block_until_ready(metrics)
    seconds = time.perf_counter() - start
    if seconds < best:
      best, share = seconds, clock.seconds / seconds
  train_rate = args.steps * config.env_steps_per_train_step / best

  # the limit: raw rollouts of every task at this batch, one after the other as in the step
  limit_seconds = sum(config.num_envs * config.unroll_length
                      / bench_physics.raw_rollout(env, config.num_envs, config.unroll_length, nthread)
                      for env in trainer.envs)
  limit = config.env_steps_per_train_step / limit_seconds

  print(f"# {platform.node()}: {os.cpu_count()} CPUs, jax {jax.__version__} "
        f"({jax.default_backend()}), mujoco {mujoco.__version__}, {nthread} native threads")
  print(f"# preset {args.preset}: {len(config.tasks)} tasks x {config.num_envs} envs x "
        f"{config.unroll_length} steps = {config.env_steps_per_train_step:,} env steps per "
        f"train step; {config.update_epochs} epochs x {config.num_minibatches} minibatches; "
        f"decoder {config.decoder}, b = {config.n_synergies}")
  print("| compile s | train env/s | physics share | outside physics | rollout env/s | ratio |")
  print("|---|---|---|---|---|---|")
  print(f"| {compile_s:.1f} | {train_rate:,.0f} | {share:.0%} | {1 - share:.0%} | {limit:,.0f} | "
        f"{train_rate / limit:.2f} |")


if __name__ == "__main__":
  main()
