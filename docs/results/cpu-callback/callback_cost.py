"""What stepping MuJoCo one control step per host call costs, on the native backend.

  python docs/results/cpu-callback/callback_cost.py      # ~1 min on the 2-core VM

valve3 at the `cpu` scale's batch (128 envs x 20 control steps of the fast profile's
substeps), from the task's reset states through the env's controls for uniform random
actions, timed three ways, interleaved, 9 repeats, median: the native backend's host-step
function called once per control step (as the jitted train step calls it), bare
`mujoco.batch.Batch.rollout` once per control step, and one `Batch.rollout` over the whole
unroll (which no policy that acts every step can use: the limit).
"""

import statistics
import time

import jax
import mujoco
import numpy as np

import tasks
from discosyn_jax.config import TrainConfig

BATCH, STEPS, REPEATS = 128, 20, 9


def main() -> None:
  env = tasks.make_envs(TrainConfig(tasks=("valve3",), backend="native"))[0]
  physics, substeps = env.physics, env.physics.n_substeps
  key = jax.random.PRNGKey(0)
  raw = np.asarray(jax.jit(jax.vmap(env.reset))(jax.random.split(key, BATCH)).pipeline_state.raw)
  actions = jax.random.uniform(key, (STEPS, BATCH, env.action_size), minval=-1, maxval=1)
  ctrl = np.asarray(env.action_to_ctrl(actions), np.float32)
  state = np.ascontiguousarray(raw).view(np.float64)
  held = ctrl.transpose(1, 0, 2).astype(np.float64).repeat(substeps, axis=1)
  batch = physics._batch(BATCH)
  spec = mujoco.mjtState.mjSTATE_CTRL

  def host_steps():
    now = raw
    for t in range(STEPS):
      now = physics._host_step(now, ctrl[t])[0]

  def batch_steps():
    batch.state[:] = state
    for t in range(STEPS):
      batch.rollout(substeps, control=np.ascontiguousarray(held[:, t * substeps:(t + 1) * substeps]),
                    control_spec=spec)

  def whole_unroll():
    batch.state[:] = state
    batch.rollout(STEPS * substeps, control=held, control_spec=spec)

  ways = {"host step x20 (the callback's function)": host_steps,
          "Batch.rollout x20": batch_steps, "Batch.rollout x1 (whole unroll)": whole_unroll}
  for way in ways.values():
    way()
  seconds = {name: [] for name in ways}
  for _ in range(REPEATS):
    for name, way in ways.items():
      start = time.perf_counter()
      way()
      seconds[name].append(time.perf_counter() - start)
  limit = seconds["Batch.rollout x1 (whole unroll)"]
  for name, values in seconds.items():
    ratio = statistics.median([a / b for a, b in zip(values, limit)])
    print(f"{name}: median {statistics.median(values) * 1000:.0f} ms; ratio to x1 {ratio:.2f}")


if __name__ == "__main__":
  main()
