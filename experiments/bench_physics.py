"""Benchmark: env steps/s of the native and mjx backends beside raw MuJoCo C.

For every scene and batch size it prints, in env (control) steps per second:
  rollout  raw `mujoco.rollout` of the same model, batch and substeps: the machine's limit
  batch    raw `mujoco.batch.Batch.step`, the engine the native backend calls
  native   the jitted, vmapped HandEnv.step on the native backend (a lax.scan of steps)
  mjx      the same on the MJX backend
and the compile time of one jitted env step per backend. One env step = 10 physics steps.

  python experiments/bench_physics.py                       # CPU: mjx at batch 16 only
  python experiments/bench_physics.py --mjx-batches 16 64 256 --steps 100   # on a GPU
  python experiments/bench_physics.py --tasks set2 unseen sparse --mjx-batches   # native only
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import jax
import jax.numpy as jnp
import mujoco
import mujoco.batch
import numpy as np
from mujoco import rollout

import tasks


def _timed(fn, repeats: int = 2) -> float:
  """Best wall time of `repeats` calls (after one warm-up call)."""
  fn()
  best = np.inf
  for _ in range(repeats):
    start = time.perf_counter()
    fn()
    best = min(best, time.perf_counter() - start)
  return best


def raw_rollout(env, batch: int, steps: int, nthread: int) -> float:
  model, n = env.mj_model, env.task.config.n_substeps
  data = [mujoco.MjData(model) for _ in range(nthread)]
  mujoco.mj_forward(model, data[0])
  spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
  state = np.empty(mujoco.mj_stateSize(model, spec))
  mujoco.mj_getState(model, data[0], state, spec)
  lo, hi = model.actuator_ctrlrange.T
  ctrl = np.random.default_rng(0).uniform(lo, hi, (batch, steps, model.nu)).repeat(n, axis=1)
  with rollout.Rollout(nthread=nthread) as pool:
    seconds = _timed(lambda: pool.rollout(model, data, np.tile(state, (batch, 1)), ctrl))
  return batch * steps / seconds


def raw_batch(env, batch: int, steps: int, nthread: int) -> float:
  model, n = env.mj_model, env.task.config.n_substeps
  sims = mujoco.batch.Batch(model, batch, nthread=nthread)
  lo, hi = model.actuator_ctrlrange.T
  ctrl = np.random.default_rng(0).uniform(lo, hi, (steps, batch, model.nu))

  def run():
    sims.reset()
    for t in range(steps):
      sims.ctrl[:] = ctrl[t]
      sims.step(nstep=n)

  return batch * steps / _timed(run)


def env_steps(env, batch: int, steps: int) -> tuple[float, float]:
  """(env steps/s, compile seconds of one jitted vmapped env step)."""
  step = jax.vmap(env.step)
  state = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), batch))
  actions = jax.random.uniform(jax.random.PRNGKey(1), (steps, batch, env.action_size), minval=-1, maxval=1)
  start = time.perf_counter()
  jax.jit(step).lower(state, actions[0]).compile()
  compile_s = time.perf_counter() - start
  run = jax.jit(lambda s, a: jax.lax.scan(lambda s, a: (step(s, a), None), s, a)[0])
  seconds = _timed(lambda: jax.block_until_ready(run(state, actions)))
  return batch * steps / seconds, compile_s


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=["set1"], help="tasks or task sets")
  parser.add_argument("--batches", type=int, nargs="+", default=[16, 64, 256])
  parser.add_argument("--mjx-batches", type=int, nargs="*", default=[16])
  parser.add_argument("--steps", type=int, default=100, help="control steps per timed run")
  parser.add_argument("--mjx-steps", type=int, default=5, help="control steps per timed mjx run")
  args = parser.parse_args()
  nthread = int(os.environ.get("DISCOSYN_NATIVE_THREADS", os.cpu_count() or 1))

  print(f"# {platform.node()}: {os.cpu_count()} CPUs, jax {jax.__version__} on "
        f"{jax.default_backend()} ({jax.devices()[0].device_kind}), mujoco {mujoco.__version__}, "
        f"{nthread} native threads; env steps/s, 1 env step = 10 physics steps of 4 ms\n")
  print("| task | batch | rollout | batch | native | native/rollout | mjx | compile native s | compile mjx s |")
  print("|---|---|---|---|---|---|---|---|---|")
  for name in tasks.expand(args.tasks):
    native = tasks.make(name, backend="native")
    mjx_env = tasks.make(name, backend="mjx") if args.mjx_batches else None
    for batch in args.batches:
      limit = raw_rollout(native, batch, args.steps, nthread)
      batched = raw_batch(native, batch, args.steps, nthread)
      rate, compile_native = env_steps(native, batch, args.steps)
      mjx_rate = compile_mjx = float("nan")
      if mjx_env is not None and batch in args.mjx_batches:
        mjx_rate, compile_mjx = env_steps(mjx_env, batch, args.mjx_steps)
      print(f"| {name} | {batch} | {limit:,.0f} | {batched:,.0f} | {rate:,.0f} | {rate / limit:.2f} | "
            f"{mjx_rate:,.0f} | {compile_native:.2f} | {compile_mjx:.1f} |", flush=True)


if __name__ == "__main__":
  main()
