"""Calibrate the tasks of sets #2, unseen and sparse: what a random policy and a scripted
motion achieve on each (native backend, whole episodes).

Per task and policy it prints: the success rate in the episode's last state (what the
`success` metric reports) and at any step, the ended-early rate (a dropped dice), the
task's own progress measure (mean and max over episodes), peak hand joint speed, peak
object speed and the deepest hand-object contact penetration.

  python studies/task_calibration.py --episodes 128
  python studies/task_calibration.py --tasks weight_pull --episodes 64 --policies scripted
  python studies/task_calibration.py --tasks valve3 --hand leap16   # another hand
"""

from __future__ import annotations

import argparse

import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax import tasks
from discosyn_jax.env import hands
from discosyn_jax.env.physics.native import deepest_penetration
from discosyn_jax.env.rollouts import run_episode
from studies import physics_study

DEFAULT_TASKS = ("dice", "weight_pull", "screw", "valve_cylinder", "valve_cw", "screw_topdown", "valve_goal")


def progress(env, qpos: np.ndarray, info) -> tuple[str, np.ndarray]:
  """(name, per-episode best value over the episode) of the task's own measure of progress."""
  task = env.task
  if hasattr(task, "dice_qpos"):
    per_step = jax.vmap(lambda q, g: task.error(_view(q), {"goal": g}))  # over the batch
    err = np.asarray(jax.vmap(per_step, in_axes=(0, None))(qpos, info["goal"]))  # (T, B)
    return "min goal error rad", err.min(0)
  if hasattr(task, "weight_qpos"):
    return "max lift m", qpos[..., task.weight_qpos].max(0)
  if hasattr(task, "slide_qpos"):
    return "max depth m", qpos[..., task.slide_qpos].max(0)
  if hasattr(task, "error"):  # the goal valve
    err = np.abs(np.angle(np.exp(1j * (info["goal"][None] - qpos[..., task.valve_qpos]))))
    return "min goal error rad", err.min(0)
  net = task.config.direction * (qpos[..., task.valve_qpos] - info["start_angle"][None])
  return "max net turn rad", net.max(0)


def _view(qpos):
  from discosyn_jax.env.physics import PhysicsView

  return PhysicsView(qpos=qpos, qvel=jnp.zeros(0), sensordata=jnp.zeros(0))


def rollout(env, actions_fn, episodes: int, seed: int):
  """Whole episodes without auto-reset; per-step pipeline states, success, done."""
  start, states = run_episode(env, jax.random.split(jax.random.PRNGKey(seed), episodes), actions_fn, seed=seed + 1)
  return (jax.device_get(start.info), jax.device_get(states.pipeline_state),
          np.asarray(states.metrics["success"]), np.asarray(states.done))


def report(label, env, info, pstate, success, done):
  ended = done.max(0) > 0
  # an episode that ended early is judged by its state when it ended
  final_success = physics_study.final_success(success, done, env.episode_length)
  hand_v = hands.qvel_indices(env.mj_model)
  obj_v = [i for i in range(env.mj_model.nv) if i not in set(hand_v)]
  measure, best = progress(env, pstate.qpos, info)
  print(f"{label:34s} success last {final_success.mean():6.1%} any {success.max(0).mean():6.1%}  "
        f"ended early {ended.mean():6.1%}  {measure} mean {best.mean():6.3f} max {best.max():6.3f}  "
        f"hand speed max {np.abs(pstate.qvel[..., hand_v]).max():5.1f} rad/s  object speed max "
        f"{np.abs(pstate.qvel[..., obj_v]).max():5.1f}  penetration max "
        f"{1000 * deepest_penetration(env.mj_model, pstate.raw, stride=7):4.1f} mm", flush=True)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=list(DEFAULT_TASKS))
  parser.add_argument("--policies", nargs="+", default=["random", "scripted"], choices=["random", "scripted"])
  parser.add_argument("--episodes", type=int, default=128)
  parser.add_argument("--seed", type=int, default=0)
  parser.add_argument("--hand", default=hands.DEFAULT, help="a shipped hand (scripted motions: ours)")
  args = parser.parse_args(argv)

  for name in args.tasks:
    env = tasks.make(name, backend="native", hand=args.hand)
    uniform = lambda t, key, n, size=env.action_size: jax.random.uniform(
        key, (n, size), minval=-1.0, maxval=1.0)
    if "random" in args.policies:
      report(f"{name} random", env, *rollout(env, uniform, args.episodes, args.seed))
    if "scripted" in args.policies:
      script = jnp.asarray(env.task.motion.actions(env.episode_length, env.dt, env.hand.name))
      report(f"{name} scripted", env,
             *rollout(env, lambda t, k, n: jnp.broadcast_to(script[t], (n, script.shape[1])),
                      args.episodes, args.seed))


if __name__ == "__main__":
  main()
