"""Benchmark: physics and training env steps/s per backend and batch, beside raw MuJoCo C.

  discosyn bench                                  # set1-disco3-linear, native, its batch (128)
  discosyn bench --batches 64 128 256 --repeats 5
  discosyn bench --backends native mjx --batches 16 --steps 1 --repeats 1   # MJX on a CPU: small
  discosyn bench --backends mjx --impls jax warp --no-train --tasks valve3 --batches 16
  discosyn bench --no-train --tasks set2 unseen sparse --batches 64         # physics only

For every backend (MJX: per implementation, `mjx/jax`, `mjx/warp`) and batch size (envs per
task) it prints, in env (control) steps per second:
  rollout    raw `mujoco.rollout` of the same models, states and controls (batch envs x
             unroll_length steps per task from the tasks' reset states, one task after the
             other as in the train step): the machine's limit
  physics    the jitted, vmapped `HandEnv.step` of the backend over the same steps
  train      whole train steps of the preset (rollouts, GAE, PPO epochs, discriminator)
  train/rollout, physics/rollout   the ratios, median over --repeats with min-max: every
             repeat times rollout, physics and training one after the other, so a change in
             the machine's load hits both sides of a ratio
  callback   native only: the share of train-step time spent inside the host callbacks
  update     seconds of the PPO update alone (epochs x minibatches, jitted apart, on samples
             of the step's shapes) and its share of a train step: the part outside physics
  compile    seconds to lower and compile the train step (and the physics step)
  peak mem   GiB: the process's peak resident memory so far (CPU), or the device's peak
             bytes in use (accelerators)
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import resource
import statistics
import time
from typing import TYPE_CHECKING

import numpy as np

from discosyn_jax.checks import BadInput

if TYPE_CHECKING:
  from discosyn_jax.training.trainer import Trainer

# JAX, MuJoCo and the trainer are imported where they are used: `discosyn --help` builds
# this parser without them.


def native_threads() -> int:
  from discosyn_jax import checks

  return checks.env_int("DISCOSYN_NATIVE_THREADS", os.cpu_count() or 1)


def bench_inputs(envs, batch: int, steps: int):
  """(each env's reset states, the actions): what the physics runner steps and the raw
  rollout replays, so that both time the same trajectories (random postures from the
  tasks' own initial states, not the model's rest pose, where the hand touches nothing)."""
  import jax

  key = jax.random.PRNGKey(0)
  states = [jax.jit(jax.vmap(env.reset))(jax.random.split(key, batch)) for env in envs]
  actions = jax.random.uniform(key, (steps, batch, envs[0].action_size), minval=-1, maxval=1)
  return states, actions


class RawRollout:
  """`mujoco.rollout` of one task's model: `batch` envs x `steps` control steps from the
  env's reset `state` (a batch of them), the env's controls for `actions` held for the
  task's substeps."""

  def __init__(self, env, state, actions, nthread: int):
    import mujoco
    from mujoco import rollout

    self.model, n = env.mj_model, env.task.config.n_substeps
    self.data = [mujoco.MjData(self.model) for _ in range(nthread)]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    view = env.physics.view(state.pipeline_state)
    qpos, qvel = np.asarray(view.qpos, np.float64), np.asarray(view.qvel, np.float64)
    self.state = np.empty((len(qpos), mujoco.mj_stateSize(self.model, spec)))
    data = self.data[0]
    for row, (q, v) in enumerate(zip(qpos, qvel)):
      data.qpos[:], data.qvel[:] = q, v
      mujoco.mj_forward(self.model, data)
      mujoco.mj_getState(self.model, data, self.state[row], spec)
    ctrl = np.asarray(env.action_to_ctrl(actions), np.float64)  # (steps, batch, nu)
    self.ctrl = np.ascontiguousarray(ctrl.transpose(1, 0, 2).repeat(n, axis=1))
    self.pool = rollout.Rollout(nthread=nthread)

  def __call__(self):
    return self.pool.rollout(self.model, self.data, self.state, self.ctrl)

  def close(self):
    self.pool.close()


def physics_runner(envs, states, actions):
  """(a function that steps every env from its `states` through `actions`, compile
  seconds)."""
  import jax

  def run(states, actions):
    out = []
    for env, state in zip(envs, states):
      step = jax.vmap(env.step)
      out.append(jax.lax.scan(lambda s, a: (step(s, a), None), state, actions)[0])
    return out

  start = time.perf_counter()
  compiled = jax.jit(run).lower(states, actions).compile()
  compile_s = time.perf_counter() - start
  return lambda: jax.block_until_ready(compiled(states, actions)), compile_s


class CallbackClock:
  """Wall time spent in the native backends' host callbacks (installed before tracing)."""

  def __init__(self, envs):
    self.seconds = 0.0
    for env in envs:
      if env.backend == "native":
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


def update_runner(trainer: Trainer, state):
  """The PPO update of a train step alone, on random samples of the step's shapes."""
  import jax

  from discosyn_jax.agent import ppo

  n = trainer.config.num_envs * trainer.config.unroll_length
  keys = iter(jax.random.split(jax.random.PRNGKey(0), 6 * len(trainer.obs_sizes)))
  normal = lambda *shape: jax.random.normal(next(keys), (n, *shape))
  samples = [ppo.Samples(obs=normal(size), z=normal(trainer.model.z_size),
                         action=normal(trainer.action_size), log_prob=normal(),
                         advantage=normal(), target=normal())
             for size in trainer.obs_sizes]
  # copies: the train step donates the state it is given
  params, opt_state = jax.tree.map(lambda x: x.copy(), (state.params, state.opt_state))
  args = (params, opt_state, samples, jax.random.PRNGKey(1))
  compiled = jax.jit(trainer._update).lower(*args).compile()
  return lambda: jax.block_until_ready(compiled(*args))


def peak_memory_gib() -> float:
  import jax

  device = jax.devices()[0]
  stats = device.memory_stats() if device.platform != "cpu" else None
  if stats and "peak_bytes_in_use" in stats:
    return stats["peak_bytes_in_use"] / 2**30
  return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB on Linux


def _seconds(fn) -> float:
  start = time.perf_counter()
  fn()
  return time.perf_counter() - start


def _median_range(values) -> str:
  return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


@contextlib.contextmanager
def mjx_impl(impl: str | None):
  """MJX's implementation for the envs built inside (DISCOSYN_MJX_IMPL; None: as set)."""
  before = os.environ.get("DISCOSYN_MJX_IMPL")
  if impl:
    os.environ["DISCOSYN_MJX_IMPL"] = impl
  try:
    yield
  finally:
    if before is None:
      os.environ.pop("DISCOSYN_MJX_IMPL", None)
    else:
      os.environ["DISCOSYN_MJX_IMPL"] = before


def backend_label(env) -> str:
  return f"mjx/{env.physics.impl}" if env.backend == "mjx" else env.backend


def bench_row(config, args, impl: str | None = None) -> dict:
  """Every figure of one backend (MJX's `impl`) and batch: see the module docstring."""
  import jax

  from discosyn_jax import assemble, tasks
  with mjx_impl(impl):
    trainer = assemble.trainer(config, devices=args.devices) if args.train else None
    envs = trainer.envs if trainer else tasks.make_envs(config)
  clock = CallbackClock(envs)
  T, B = config.unroll_length, config.num_envs
  total = len(envs) * B * T  # env steps of one pass over every task
  states, actions = bench_inputs(envs, B, T)
  raw = [RawRollout(env, state, actions, native_threads()) for env, state in zip(envs, states)]
  physics, physics_compile = physics_runner(envs, states, actions)
  row = dict(backend=backend_label(envs[0]), batch=B, physics_compile=physics_compile)
  if trainer:
    state = trainer.init()
    start = time.perf_counter()
    train_step = trainer.train_step.lower(state).compile()
    row["compile"] = time.perf_counter() - start
    state, metrics = train_step(state)  # warm-up
    jax.block_until_ready(metrics)
    update = update_runner(trainer, state)
    update()
  for fn in raw:
    fn()
  physics()

  rollout_rates, physics_rates, train_rates, shares, updates = [], [], [], [], []
  for _ in range(args.repeats):
    rollout_rates.append(total / sum(_seconds(fn) for fn in raw))
    physics_rates.append(total / _seconds(physics))
    if trainer:
      clock.seconds = 0.0
      start = time.perf_counter()
      for _ in range(args.steps):
        state, metrics = train_step(state)
      jax.block_until_ready(metrics)
      seconds = time.perf_counter() - start
      train_rates.append(args.steps * config.env_steps_per_train_step / seconds)
      shares.append(clock.seconds / seconds)
      updates.append(_seconds(update))
  for fn in raw:
    fn.close()
  row.update(rollout=statistics.median(rollout_rates), physics=statistics.median(physics_rates),
             physics_ratio=_median_range([p / r for p, r in zip(physics_rates, rollout_rates)]),
             peak=peak_memory_gib())
  if trainer:
    row.update(train=statistics.median(train_rates),
               train_ratio=_median_range([t / r for t, r in zip(train_rates, rollout_rates)]),
               callback=statistics.median(shares) if row["backend"] == "native" else float("nan"),
               update=statistics.median(updates),
               update_share=statistics.median(
                   [u * r / config.env_steps_per_train_step for u, r in zip(updates, train_rates)]))
  return row


def build_parser(parser: argparse.ArgumentParser | None = None) -> argparse.ArgumentParser:
  parser = parser or argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--preset", default="set1-disco3-linear",
                      help="the training config, a name in discosyn_jax/experiments/presets.py (default: "
                      "%(default)s)")
  parser.add_argument("--tasks", nargs="+", help="tasks or task sets (default: the preset's)")
  parser.add_argument("--backends", nargs="+", default=["native"], choices=["native", "mjx"],
                      help="physics backends, a row each (default: native)")
  parser.add_argument("--impls", nargs="+", choices=["jax", "warp"],
                      help="MJX's implementations, a row each for backend mjx (default: "
                      "DISCOSYN_MJX_IMPL's, else jax)")
  parser.add_argument("--batches", type=int, nargs="+",
                      help="envs per task, a row each (default: the preset's num_envs)")
  parser.add_argument("--epochs", type=int, help="PPO epochs (default: the preset's)")
  parser.add_argument("--physics", nargs="+", choices=["fast", "reference"],
                      help="the tasks' physics profiles, a row each (default: the preset's)")
  parser.add_argument("--reset-pool", action="store_true",
                      help="episodes restart from a pool of initial states (TrainConfig.reset_pool)")
  parser.add_argument("--steps", type=int, default=3,
                      help="train steps per timing (default: %(default)s)")
  parser.add_argument("--repeats", type=int, default=3,
                      help="interleaved timings per row (default: %(default)s)")
  parser.add_argument("--devices", type=int,
                      help="devices to split the env batch over (default: all of them)")
  parser.add_argument("--no-train", dest="train", action="store_false",
                      help="physics only, no train steps")
  return parser


def run(args) -> None:
  import jax
  import mujoco

  from discosyn_jax import tasks
  from discosyn_jax.experiments import presets

  base = presets.preset(args.preset)
  if args.tasks:
    base = base.replace(tasks=tuple(tasks.expand(args.tasks)))
  if args.epochs is not None:
    base = base.replace(update_epochs=args.epochs)
  if args.reset_pool:
    base = base.replace(reset_pool=True)
  for name in ("steps", "repeats"):
    if getattr(args, name) < 1:
      raise BadInput(f"--{name} must be at least 1, not {getattr(args, name)}")
  rows = [(impl, base.replace(backend=backend, num_envs=batch, physics=physics).validate())
          for backend in args.backends
          for impl in ((args.impls or [None]) if backend == "mjx" else [None])
          for batch in (args.batches or [base.num_envs])
          for physics in (args.physics or [base.physics])]
  c = rows[0][1]
  print(f"# {platform.node()}: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; "
        f"jax {jax.__version__} on {jax.device_count()} x {jax.devices()[0].device_kind}, "
        f"mujoco {mujoco.__version__}, {native_threads()} native threads")
  print(f"# preset {args.preset}: {len(c.tasks)} tasks x envs x {c.unroll_length} steps per "
        f"train step; {c.update_epochs} epochs x {c.num_minibatches} minibatches; decoder "
        f"{c.decoder}, b = {c.n_synergies}; ratios: median (min-max) of {args.repeats} repeats")
  print("| backend | batch | physics | rollout env/s | physics env/s | physics/rollout | train env/s | "
        "train/rollout | callback share | update s (share) | compile s (train, physics) | "
        "peak mem GiB |")
  print("|---|---|---|---|---|---|---|---|---|---|---|---|")
  for impl, config in rows:
    r = bench_row(config, args, impl)
    train = (f"{r['train']:,.0f} | {r['train_ratio']} | {r['callback']:.0%} | "
             f"{r['update']:.3f} ({r['update_share']:.0%}) | "
             f"{r['compile']:.1f}, {r['physics_compile']:.1f}" if args.train
             else f"- | - | - | - | -, {r['physics_compile']:.1f}")
    print(f"| {r['backend']} | {r['batch']} | {config.physics} | {r['rollout']:,.0f} | {r['physics']:,.0f} | "
          f"{r['physics_ratio']} | {train} | {r['peak']:.2f} |", flush=True)


def main(argv=None):
  run(build_parser().parse_args(argv))


if __name__ == "__main__":
  main()
