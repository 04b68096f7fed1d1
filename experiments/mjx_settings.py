"""MJX solver settings for the hand, measured: speed, compile time and each task's stability.

For every task and setting (overrides of the scene's <option>, and timestep x substeps with
the control step kept at 40 ms) it prints:
  contacts     MJX contact slots (every candidate pair gets one, touching or not)
  env/s        vmapped MJX env steps per second at --batch (a lax.scan of --steps steps)
  compile s    the jitted scan
  hand err, object err   the largest difference (rad or m) over the task's scripted motion
               (--episode control steps) from the native backend with the scene's settings:
               the stability check (NaN means the simulation blew up)

  python experiments/mjx_settings.py --tasks valve3 --batch 16          # CPU: small
  python experiments/mjx_settings.py --tasks set1 set2 --batch 1024 --steps 50   # on a GPU
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

import tasks
from discosyn_jax import hand, scripted
from discosyn_jax.physics.mjx_backend import MjxBackend

# name -> (model.opt overrides, substeps per 40 ms control step)
SETTINGS = {
    "scene (8 it, 8 ls, 4 ms x 10)": ({}, 10),
    "4 it, 4 ls": ({"iterations": 4, "ls_iterations": 4}, 10),
    "2 it, 4 ls": ({"iterations": 2, "ls_iterations": 4}, 10),
    "8 ms x 5": ({"timestep": 0.008}, 5),
}


def with_settings(name: str, opt: dict, substeps: int, impl: str | None):
  env = tasks.make(name, backend="mjx")
  model = env.task.build_model()
  for key, value in opt.items():
    setattr(model.opt, key, value)
  env.physics = MjxBackend(model, substeps, impl=impl)
  return env


def speed(env, batch: int, steps: int) -> tuple[float, float]:
  state = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), batch))
  actions = jax.random.uniform(jax.random.PRNGKey(1), (steps, batch, env.action_size), minval=-1, maxval=1)
  step = jax.vmap(env.step)
  start = time.perf_counter()
  run = jax.jit(lambda s, a: jax.lax.scan(lambda s, a: (step(s, a), None), s, a)[0].obs)
  run = run.lower(state, actions).compile()
  compile_s = time.perf_counter() - start
  jax.block_until_ready(run(state, actions))
  start = time.perf_counter()
  jax.block_until_ready(run(state, actions))
  return batch * steps / (time.perf_counter() - start), compile_s


def trajectory(env, name: str, steps: int) -> np.ndarray:
  actions = jnp.asarray(scripted.for_task(name, steps, env.dt))

  def roll(key):
    state = env.reset(key)
    return jax.lax.scan(lambda s, a: (env.step(s, a),) * 2, state, actions)[1]

  states = jax.jit(roll)(jax.random.PRNGKey(3))
  return np.asarray(jax.vmap(env.physics.view)(states.pipeline_state).qpos)


def contact_slots(env) -> int:
  data = env.physics._data0
  contact = getattr(getattr(data, "_impl", data), "contact", None)
  return int(contact.dist.shape[0]) if contact is not None else -1


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=["valve3"])
  parser.add_argument("--settings", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
  parser.add_argument("--batch", type=int, default=16)
  parser.add_argument("--steps", type=int, default=5, help="control steps per timed run")
  parser.add_argument("--episode", type=int, default=50, help="control steps of the stability check")
  parser.add_argument("--impl", choices=["jax", "warp"], help="MJX implementation (default: auto)")
  args = parser.parse_args()
  print(f"# jax {jax.__version__} on {jax.devices()[0].device_kind}; batch {args.batch}")
  print("| task | setting | contacts | env/s | compile s | hand err | object err |")
  print("|---|---|---|---|---|---|---|")
  for name in tasks.expand(args.tasks):
    native = tasks.make(name, backend="native")
    reference = trajectory(native, name, args.episode)
    hand_q = hand.qpos_indices(native.mj_model)
    other_q = np.setdiff1d(np.arange(reference.shape[1]), hand_q)
    for setting in args.settings:
      opt, substeps = SETTINGS[setting]
      env = with_settings(name, opt, substeps, args.impl)
      rate, compile_s = speed(env, args.batch, args.steps)
      qpos = trajectory(env, name, args.episode)
      err = lambda idx: float(np.abs(qpos[:, idx] - reference[:, idx]).max()) if len(idx) else 0.0
      print(f"| {name} | {setting} | {contact_slots(env)} | {rate:,.0f} | {compile_s:.1f} | "
            f"{err(hand_q):.3f} | {err(other_q):.3f} |", flush=True)


if __name__ == "__main__":
  main()
