"""The physics-settings study: what each setting of timestep x substeps and solver costs, and
what it changes in the tasks, beside the reference (4 ms x 10, 8 iterations, pyramidal).

Every setting keeps the control step at 0.04 s. Per task and setting it prints
  cost      native env steps/s (the jitted, vmapped `HandEnv.step`) and raw `mujoco.rollout`
            of the same model, at --batch envs x --steps control steps; "x ref" is the
            median over --repeats of native env/s over the reference's in the same repeat
            (the settings are timed one after the other in every repeat, so a change of the
            machine's load hits every setting alike); --mjx adds MJX's compile s and env/s
  fidelity  scripted: the success rate of the task's scripted motion (TASKS_NOTES'
            calibration) over --episodes random starts; random: the uniform random policy's;
            drift: mean |final object qpos - reference's| after the same scripted motion from
            the same starts (rad or m; the valve's angle, the screw's depth...); diverged:
            episodes whose simulation blew up over --long-episodes of random actions of
            --long-steps steps; pen mm: the deepest hand-object penetration there; speed:
            the largest hand joint speed there (rad/s), the energy check
The last lines say, per task, which settings stay within the tolerances (--tol-*), and the
cheapest of them.

  python -m studies.physics_study --tasks set1 --episodes 128      # ~10 min on 2 cores
  python -m studies.physics_study --tasks valve3 --settings ref 8x5 --episodes 16 --repeats 1
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np

# name -> TaskConfig overrides ("<timestep ms>x<substeps>"); the control step stays 0.04 s
SETTINGS = {
    "ref": dict(n_substeps=10, solver_iterations=8, ls_iterations=8, cone="pyramidal",
                refsafe=True),
    "5x8": dict(n_substeps=8),
    "8x5": dict(n_substeps=5),
    "10x4": dict(n_substeps=4),
    "20x2": dict(n_substeps=2),
    "ref-it4": dict(n_substeps=10, solver_iterations=4, ls_iterations=4),
    "8x5-it4": dict(n_substeps=5, solver_iterations=4, ls_iterations=4),
    "10x4-it4": dict(n_substeps=4, solver_iterations=4, ls_iterations=4),
    "10x4-it2": dict(n_substeps=4, solver_iterations=2, ls_iterations=4),
    "8x5-elliptic": dict(n_substeps=5, cone="elliptic"),
    # contacts as stiff as at 4 ms (refsafe off: the solref time constant is not raised)
    "8x5-stiff": dict(n_substeps=5, refsafe=False),
    "10x4-stiff": dict(n_substeps=4, refsafe=False),
}


@dataclasses.dataclass
class Row:
  task: str
  setting: str
  native: list = dataclasses.field(default_factory=list)  # env/s per repeat
  rollout: list = dataclasses.field(default_factory=list)
  ratio: list = dataclasses.field(default_factory=list)  # native / reference's native
  mjx: tuple = (float("nan"), float("nan"))  # (compile s, env/s)
  scripted: float = float("nan")
  random: float = float("nan")
  drift: float = float("nan")
  diverged: int = 0
  penetration_mm: float = float("nan")
  speed: float = float("nan")


def make_env(name: str, setting: str, backend: str = "native"):
  from discosyn_jax import tasks
  return tasks.make(name, backend=backend, physics="reference", **SETTINGS[setting])


def final_success(metrics_success, done, episode_length):
  """Success judged in each episode's last state, or where it ended early."""
  ended = done.max(0) > 0
  last = np.where(ended, done.argmax(0), episode_length - 1)
  return metrics_success[last, np.arange(metrics_success.shape[1])]


def object_qpos(env) -> np.ndarray:
  from discosyn_jax.env import hands

  return np.setdiff1d(np.arange(env.mj_model.nq), hands.qpos_indices(env.mj_model))


def fidelity(env, name: str, episodes: int, long_episodes: int, long_steps: int, seed: int):
  """(scripted success, random success, final object qpos after the script (episodes, k),
  diverged count, deepest penetration m, largest hand joint speed) of one env."""
  import jax
  import jax.numpy as jnp

  from discosyn_jax.env import hands
  from discosyn_jax.env.physics.native import deepest_penetration
  from discosyn_jax.env.rollouts import run_episode

  keys = jax.random.split(jax.random.PRNGKey(seed), episodes)
  script = jnp.asarray(env.task.motion.actions(env.episode_length, env.dt, env.hand.name))
  _, states = run_episode(env, keys, lambda t, k, n: jnp.broadcast_to(script[t], (n, script.shape[1])))
  done = np.asarray(states.done)
  scripted_rate = final_success(np.asarray(states.metrics["success"]), done, env.episode_length).mean()
  final_obj = np.asarray(states.pipeline_state.qpos[-1])[:, object_qpos(env)]

  def uniform(t, key, n):
    return jax.random.uniform(key, (n, env.action_size), minval=-1.0, maxval=1.0)

  _, states = run_episode(env, keys, uniform)
  random_rate = final_success(np.asarray(states.metrics["success"]), np.asarray(states.done),
                              env.episode_length).mean()
  # long random rollouts, no reset: what blows up, how deep contacts go, how fast joints get
  long_keys = jax.random.split(jax.random.PRNGKey(seed + 1), long_episodes)
  _, states = run_episode(env, long_keys, uniform, steps=long_steps)
  diverged = int(np.asarray(states.metrics["diverged"]).max(0).sum())
  qvel = np.asarray(states.pipeline_state.qvel)[..., hands.qvel_indices(env.mj_model)]
  speed = float(np.nanmax(np.abs(qvel)))
  pen = deepest_penetration(env.mj_model, np.asarray(states.pipeline_state.raw), stride=11)
  return scripted_rate, random_rate, final_obj, diverged, pen, speed


def mjx_cost(name: str, setting: str, batch: int, steps: int) -> tuple[float, float]:
  """(compile s, env/s) of MJX's vmapped step scan (small on a CPU)."""
  from discosyn_jax.experiments.bench import bench_inputs, physics_runner

  env = make_env(name, setting, backend="mjx")
  run, compile_s = physics_runner([env], *bench_inputs([env], batch, steps))
  run()
  start = time.perf_counter()
  run()
  return compile_s, batch * steps / (time.perf_counter() - start)


def study(names, settings, args) -> list[Row]:
  from discosyn_jax.experiments.bench import RawRollout, bench_inputs, native_threads, physics_runner

  rows = {(n, s): Row(n, s) for n in names for s in settings}
  for name in names:
    envs = {s: make_env(name, s) for s in settings}
    inputs = {s: bench_inputs([envs[s]], args.batch, args.steps) for s in settings}
    runners = {s: physics_runner([envs[s]], *inputs[s])[0] for s in settings}
    raws = {s: RawRollout(envs[s], inputs[s][0][0], inputs[s][1], native_threads())
            for s in settings}
    for s in settings:  # warm-up
      runners[s]()
      raws[s]()
    for _ in range(args.repeats):
      rates = {}
      for s in settings:
        start = time.perf_counter()
        runners[s]()
        rates[s] = args.batch * args.steps / (time.perf_counter() - start)
        start = time.perf_counter()
        raws[s]()
        rows[name, s].rollout.append(args.batch * args.steps / (time.perf_counter() - start))
        rows[name, s].native.append(rates[s])
      for s in settings:
        rows[name, s].ratio.append(rates[s] / rates[settings[0]])
    for raw in raws.values():
      raw.close()
    reference = None
    for s in settings:
      row = rows[name, s]
      if args.mjx:
        row.mjx = mjx_cost(name, s, args.mjx_batch, args.mjx_steps)
      if args.fidelity:
        (row.scripted, row.random, final, row.diverged, pen, row.speed) = fidelity(
            envs[s], name, args.episodes, args.long_episodes, args.long_steps, args.seed)
        row.penetration_mm = 1000 * pen
        reference = final if reference is None else reference
        row.drift = float(np.abs(final - reference).mean())
      print_row(row, args, flush=True)
  return list(rows.values())


HEADER = ("| task | setting | native env/s | rollout env/s | x ref | mjx compile s | mjx env/s | "
          "scripted | random | drift | diverged | pen mm | speed |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|")


def print_row(row: Row, args, flush=False):
  med = statistics.median
  print(f"| {row.task} | {row.setting} | {med(row.native):,.0f} | {med(row.rollout):,.0f} | "
        f"{med(row.ratio):.2f} ({min(row.ratio):.2f}-{max(row.ratio):.2f}) | {row.mjx[0]:.1f} | "
        f"{row.mjx[1]:,.0f} | {row.scripted:.1%} | {row.random:.1%} | {row.drift:.3f} | "
        f"{row.diverged}/{args.long_episodes} | {row.penetration_mm:.1f} | {row.speed:.1f} |",
        flush=flush)


def faithful(row: Row, ref: Row, args) -> list[str]:
  """Why `row` is not faithful to the reference (empty: it is)."""
  why = []
  se = lambda p: np.sqrt(max(p * (1 - p), 1.0 / args.episodes) / args.episodes)
  if abs(row.scripted - ref.scripted) > args.tol_sigma * np.hypot(se(row.scripted), se(ref.scripted)):
    why.append(f"scripted {row.scripted:.1%} vs {ref.scripted:.1%}")
  if row.random > ref.random + args.tol_sigma * np.hypot(se(row.random), se(ref.random)):
    why.append(f"random {row.random:.1%} vs {ref.random:.1%}")
  if row.drift > args.tol_drift:
    why.append(f"drift {row.drift:.3f}")
  if row.diverged > ref.diverged:
    why.append(f"{row.diverged} diverged")
  if row.penetration_mm > max(args.tol_pen_mm, ref.penetration_mm * 1.5):
    why.append(f"penetration {row.penetration_mm:.1f} mm")
  if row.speed > args.tol_speed:
    why.append(f"joint speed {row.speed:.1f} rad/s")
  return why


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=["set1"])
  parser.add_argument("--settings", nargs="+", default=list(SETTINGS), choices=list(SETTINGS),
                      help="the first is the reference the others are compared with")
  parser.add_argument("--batch", type=int, default=64)
  parser.add_argument("--steps", type=int, default=20)
  parser.add_argument("--repeats", type=int, default=3)
  parser.add_argument("--episodes", type=int, default=128)
  parser.add_argument("--long-episodes", type=int, default=32)
  parser.add_argument("--long-steps", type=int, default=500)
  parser.add_argument("--seed", type=int, default=0)
  parser.add_argument("--no-fidelity", dest="fidelity", action="store_false",
                      help="cost only: no episodes (the fidelity columns stay empty)")
  parser.add_argument("--mjx", action="store_true", help="also MJX's compile time and speed")
  parser.add_argument("--mjx-batch", type=int, default=16)
  parser.add_argument("--mjx-steps", type=int, default=2)
  parser.add_argument("--tol-sigma", type=float, default=2.0,
                      help="scripted / random rates within this many standard errors")
  parser.add_argument("--tol-drift", type=float, default=0.15,
                      help="mean |final object qpos - reference's| after the script (rad or m)")
  parser.add_argument("--tol-pen-mm", type=float, default=8.0)
  parser.add_argument("--tol-speed", type=float, default=20.0)
  args = parser.parse_args(argv)

  import jax

  from discosyn_jax import tasks
  names = tasks.expand(args.tasks)
  print(f"# jax {jax.__version__}, batch {args.batch} x {args.steps} steps, {args.repeats} repeats, "
        f"{args.episodes} episodes; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
  print(HEADER, flush=True)
  rows = study(names, args.settings, args)
  print()
  for name in names if args.fidelity else ():
    by = {r.setting: r for r in rows if r.task == name}
    ref = by[args.settings[0]]
    ok = []
    for s in args.settings[1:]:
      why = faithful(by[s], ref, args)
      print(f"{name} {s}: " + ("faithful" if not why else "not faithful: " + "; ".join(why)))
      if not why:
        ok.append(s)
    best = max(ok, key=lambda s: statistics.median(by[s].ratio), default=args.settings[0])
    print(f"{name}: cheapest faithful setting {best} "
          f"({statistics.median(by[best].ratio):.2f}x the reference)", flush=True)


if __name__ == "__main__":
  main()
