"""Calibrate the valves: what a random policy and a scripted turn achieve.

For each valve and hinge setting, runs `--episodes` episodes of a uniform random policy
(i.i.d. actions in [-1, 1] every control step) on the native backend and prints the
random policy's success rate, mean |net turn|, peak hand joint speed, valve speed and the
deepest hand-object contact penetration; then the scripted grasp-and-sweep turn.

  python studies/valve_calibration.py --frictionloss 0 0.15 --damping 0.1 0.5
"""

from __future__ import annotations

import argparse
import itertools

import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax import tasks
from discosyn_jax.env import hands, scripted
from discosyn_jax.env.physics.native import deepest_penetration


def rollout(env, actions_fn, episodes: int, seed: int):
  """Run whole episodes; return per-step states (raw, for penetration) and metrics."""
  reset = jax.jit(jax.vmap(env.reset))
  step = jax.jit(jax.vmap(env.step))
  state = reset(jax.random.split(jax.random.PRNGKey(seed), episodes))
  start = np.asarray(state.info["start_angle"])
  qvels, raws, angles = [], [], []
  key = jax.random.PRNGKey(seed + 1)
  for t in range(env.episode_length):
    key, sub = jax.random.split(key)
    state = step(state, actions_fn(t, sub, episodes))
    qvels.append(np.asarray(state.pipeline_state.qvel))
    raws.append(np.asarray(state.pipeline_state.raw))
    angles.append(np.asarray(state.pipeline_state.qpos[:, env.task.valve_qpos]))
  return start, np.stack(angles, 1), np.stack(qvels, 1), np.stack(raws, 1), np.asarray(state.metrics["success"])


def report(name, env, start, angles, qvels, raws, success):
  hand_v = hands.qvel_indices(env.mj_model)
  net = angles[:, -1] - start
  valve_speed = np.abs(np.diff(np.concatenate([start[:, None], angles], 1), axis=1)) / env.dt
  print(f"{name:44s} success {success.mean():6.1%}  mean|net| {np.abs(net).mean():5.2f} rad  "
        f"net p99 {np.percentile(net, 99):5.2f}  joint speed p99/max "
        f"{np.percentile(np.abs(qvels[..., hand_v]), 99):5.1f}/{np.abs(qvels[..., hand_v]).max():5.1f} rad/s  "
        f"valve speed max {valve_speed.max():5.1f} rad/s  penetration max "
        f"{1000 * deepest_penetration(env.mj_model, raws, stride=5):5.1f} mm", flush=True)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--valves", nargs="+", default=list(tasks.TASK_SETS["set1"]))
  parser.add_argument("--frictionloss", type=float, nargs="+", default=[None])
  parser.add_argument("--damping", type=float, nargs="+", default=[None])
  parser.add_argument("--episodes", type=int, default=256)
  parser.add_argument("--seed", type=int, default=0)
  args = parser.parse_args(argv)

  def uniform(t, key, n):
    return jax.random.uniform(key, (n, 20), minval=-1.0, maxval=1.0)

  for valve, fl, damp in itertools.product(args.valves, args.frictionloss, args.damping):
    overrides = {k: v for k, v in (("frictionloss", fl), ("damping", damp)) if v is not None}
    env = tasks.make(valve, backend="native", **overrides)
    label = f"{valve} fl={env.task.config.frictionloss} damp={env.task.config.damping}"
    report(label + " random", env, *rollout(env, uniform, args.episodes, args.seed))
    scripted_actions = jnp.asarray(scripted.grasp_and_sweep(env.episode_length, env.dt))
    report(label + " scripted", env,
           *rollout(env, lambda t, k, n: jnp.broadcast_to(scripted_actions[t], (n, 20)),
                    args.episodes, args.seed))


if __name__ == "__main__":
  main()
