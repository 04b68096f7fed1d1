"""The GPU check: one call on a fresh GPU machine measures the GPU path end to end.

  bash benchmarks/gpu/wheels.sh          # once: the wheels a bare GPU image lacks
  # on the GPU machine (docs/SCALING.md has the exact call):
  python3 benchmarks/gpu/gpu_check.py --methods DiscoSyn3-L-reward --budget-s 500 --out $OUT
  # MuJoCo Warp beside MJX's JAX implementation, the same row (the warp-lang wheel in .whl/):
  python3 benchmarks/gpu/gpu_check.py --methods DiscoSyn3-L-reward --impls warp jax --out $OUT

Each result one JSON line in OUT/gpu_check.jsonl as soon as it is measured (a run cut
short keeps what it measured); the methods (--methods: rows of the paper's tables,
configured as `discosyn experiment` configures them at --scale and --seed) one after the
other, each trained as soon as it has started; with --impls, each under each of MJX's
implementations (`jax`, `warp`: DISCOSYN_MJX_IMPL), logged as METHOD/IMPL. On a cold machine
the start of the `gpu` scale takes minutes (docs/BENCHMARKS.md, "GPU"): a call of 15 minutes
fits one method.
  versions   python, jax, mujoco, mujoco-mjx, warp-lang, brax, the devices
  phase      per method, as each part of its start ends: Trainer build, the physics
             prior's start where the method has one, `init()`, the compiles of the train
             step and of the evaluation (none with --eval-every 0)
  start      per method: those parts together
  physics    (--physics, after the first method's start) MJX env (control) steps/s of the
             jitted, vmapped `HandEnv.step` in a scan of --physics-steps steps, for every task
             of the set at every --batches, and for valve3 at one batch under each of
             studies/physics_study.SETTINGS (compiled in parallel threads)
  train      one line per train step (env steps, wall seconds, env steps/s, training
             success), for the method's equal share of what is left of --budget-s
  eval       deterministic success and return per task every --eval-every train steps and at
             the end of the method's share
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import pathlib
import platform
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import discosyn_jax  # noqa: E402
from discosyn_jax.run import jax_setup  # noqa: E402

jax_setup.setup_jax()  # the compile cache; MJX imported quietly

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from discosyn_jax import assemble, tasks  # noqa: E402
from discosyn_jax.synergies import start  # noqa: E402
from discosyn_jax.experiments import bench, paper  # noqa: E402
from discosyn_jax.experiments.method import Method  # noqa: E402
from studies import physics_study  # noqa: E402


class Log:
  """JSON lines to a file, each also printed; flushed at once."""

  def __init__(self, path: pathlib.Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    self.file = open(path, "a")

  def __call__(self, what: str, **row):
    line = json.dumps({"what": what, **row})
    print(line, flush=True)
    self.file.write(line + "\n")
    self.file.flush()


def versions() -> dict:
  import brax
  import mujoco
  from importlib import metadata

  try:
    gpu = subprocess.run(["nvidia-smi", "--query-gpu=name,memory.total,driver_version",
                          "--format=csv,noheader"], capture_output=True, text=True,
                         timeout=30).stdout.strip()
  except (OSError, subprocess.SubprocessError):
    gpu = None
  try:
    warp = metadata.version("warp-lang")
  except metadata.PackageNotFoundError:
    warp = None
  return dict(python=platform.python_version(), jax=jax.__version__, mujoco=mujoco.__version__,
              mjx=metadata.version("mujoco-mjx"), warp=warp, brax=brax.__version__,
              devices=[str(d) for d in jax.devices()], backend=jax.default_backend(),
              gpu=gpu, cpus=os.cpu_count())


def timed(fn):
  start = time.perf_counter()
  out = fn()
  jax.block_until_ready(out)
  return out, time.perf_counter() - start


def physics_modules(names, batches, settings, steps: int):
  """[(label, lowered scan, its arguments)] for every task x batch, and valve3 at the largest
  batch but one under each of `settings` (studies/physics_study.py)."""
  jobs = [(dict(task=name, batch=batch, setting="default"), tasks.make(name, backend="mjx"))
          for name in names for batch in batches]
  for setting in settings:
    env = physics_study.make_env("valve3", setting, backend="mjx")
    jobs.append((dict(task="valve3", batch=sorted(batches)[-2:][0], setting=setting), env))
  out = []
  for label, env in jobs:
    batch = label["batch"]
    actions = jax.random.uniform(jax.random.PRNGKey(1), (steps, batch, env.action_size),
                                 minval=-1, maxval=1)
    step = jax.vmap(env.step)

    def run(key, actions, env=env, step=step, batch=batch):
      # one env reset and copied: every compile (reset included) runs in the thread pool;
      # the one reset is negligible beside batch x steps steps
      one = env.reset(key)
      state = jax.tree.map(lambda x: jnp.broadcast_to(x, (batch,) + x.shape), one)
      return jax.lax.scan(lambda s, a: (step(s, a), None), state, actions)[0].obs

    args = (jax.random.PRNGKey(0), actions)
    out.append((label, jax.jit(run).lower(*args), args))
  return out


def measure_physics(log: Log, names, batches, settings, steps: int, threads: int):
  start = time.perf_counter()
  modules = physics_modules(names, batches, settings, steps)
  traced = time.perf_counter() - start

  def compile_one(module):
    t = time.perf_counter()
    return module.compile(), time.perf_counter() - t

  with concurrent.futures.ThreadPoolExecutor(threads) as pool:
    compiled = list(pool.map(compile_one, [m for _, m, _ in modules]))
  log("physics_compile", modules=len(modules), trace_s=traced,
      wall_s=time.perf_counter() - start, threads=threads)
  for (label, _, args), (run, compile_s) in zip(modules, compiled):
    jax.block_until_ready(run(*args))  # warm-up
    _, seconds = timed(lambda: run(*args))
    log("physics", **label, steps=steps, compile_s=compile_s,
        env_steps_per_s=label["batch"] * steps / seconds)


def configs(methods, task_set: str, scale: str, seed: int, backend: str) -> dict:
  """{method: TrainConfig} as `discosyn experiment` trains these rows of the set's table."""
  table = {s: t for t, s in paper.TABLES.items()}[task_set]
  planner = paper.Planner(pathlib.Path("unused"), scale, seed)
  wanted = [Method.parse(m) for m in methods]
  steps = {s.meta["method"]: s for s in paper.select(planner.plan(table), wanted)
           if isinstance(s, paper.Train)}
  missing = [m for m in methods if m not in steps]
  if missing:
    raise ValueError(f"not rows of {table}: {', '.join(missing)} "
                     f"(rows: {', '.join(map(str, paper.PAPER_ROWS[task_set]))})")
  return {m: steps[m].config.replace(backend=backend).validate() for m in methods}


def start_method(log: Log, method: str, config, evaluations: bool = True):
  """The Trainer, its fresh state (from the prior's start where the method has one) and the
  compiled train step and evaluation (None without `evaluations`), each part logged as it
  ends: a call cut short still says where its time went."""
  took = {}

  def phase(name, fn):
    out, took[name] = timed(fn)
    log("phase", method=method, phase=name, seconds=took[name])
    return out

  trainer = phase("build", lambda: assemble.trainer(config))
  decoder = phase("prior", lambda: start.starting_decoder(trainer))
  state = phase("init", lambda: trainer.init(decoder_params=decoder))
  train_step = phase("train_compile", lambda: trainer.train_step.lower(state).compile())
  evaluate = None
  if evaluations:
    key = jax.random.PRNGKey(0)
    evaluate = phase("eval_compile", lambda: trainer.returns.lower(
        state.params, state.normalizers, key).compile())
  log("start", method=method, backend=bench.backend_label(trainer.envs[0]),
      num_envs=config.num_envs, env_steps_per_train_step=config.env_steps_per_train_step,
      decoder_init=config.decoder_init,
      **{f"{name}_s": seconds for name, seconds in took.items()}, start_s=sum(took.values()))
  return config, state, train_step, evaluate


def train_method(log: Log, method: str, config, state, train_step, evaluate, seconds: float,
                 eval_every: int, final_eval_s: float):
  """Train for `seconds` (the last `final_eval_s` kept for the final evaluation; without
  `evaluate`, training success alone)."""
  train_start = time.perf_counter()
  if evaluate is None:
    eval_every, final_eval_s = 0, 0.0

  def run_eval(step):
    if evaluate is None:
      return
    key = jax.random.fold_in(jax.random.PRNGKey(config.seed + 1), step)
    results, took = timed(lambda: evaluate(state.params, state.normalizers, key))
    results = jax.tree.map(float, jax.device_get(results))
    log("eval", method=method, step=step, env_steps=step * config.env_steps_per_train_step,
        wall_s=time.perf_counter() - train_start, eval_s=took,
        **{f"{n}/{k}": v for n, r in results.items() for k, v in r.items()})

  run_eval(0)
  deadline = train_start + seconds - final_eval_s
  step = 0
  while time.perf_counter() < deadline and step < config.steps:
    tick = time.perf_counter()
    state, metrics = train_step(state)
    metrics = jax.device_get(metrics)
    step += 1
    took = time.perf_counter() - tick
    log("train", method=method, step=step, env_steps=step * config.env_steps_per_train_step,
        wall_s=time.perf_counter() - train_start,
        env_steps_per_s=config.env_steps_per_train_step / took, finite=bool(metrics["finite"]),
        **{f"{n}/success": float(metrics[f"{n}/success"]) for n in config.tasks})
    if eval_every and step % eval_every == 0:
      run_eval(step)
  if not eval_every or step % eval_every:
    run_eval(step)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--methods", nargs="+", default=["DiscoSyn3-L-reward", "Random3-L-zfree"],
                      help="rows of the set's table (discosyn_jax/experiments/paper.py PAPER_ROWS): the "
                           "default row and its strongest control")
  parser.add_argument("--set", default="set1", choices=sorted(paper.TABLES.values()),
                      help="the task set (its table's rows)")
  parser.add_argument("--seed", type=int, default=0)
  parser.add_argument("--scale", default="gpu", choices=list(paper.SCALES),
                      help="sizes of the training (discosyn_jax/experiments/paper.py SCALES)")
  parser.add_argument("--backend", default="mjx", choices=["mjx", "native"],
                      help="physics of the training (native: a CPU dry run)")
  parser.add_argument("--impls", nargs="+", choices=["jax", "warp"],
                      help="MJX's implementations, each method under each (default: "
                           "DISCOSYN_MJX_IMPL's, else jax)")
  parser.add_argument("--physics", action="store_true",
                      help="also time the MJX physics alone (after the start, before training)")
  parser.add_argument("--batches", type=int, nargs="+", default=[2048, 8192, 16384],
                      help="envs per task of the physics timings")
  parser.add_argument("--settings", nargs="*", choices=list(physics_study.SETTINGS),
                      default=["ref", "8x5", "8x5-it4", "10x4-it4"],
                      help="physics settings timed on valve3 beside the default (none: skip)")
  parser.add_argument("--physics-steps", type=int, default=20, help="control steps per timing")
  parser.add_argument("--threads", type=int, default=12, help="parallel compiles of the physics")
  parser.add_argument("--eval-every", type=int, default=10,
                      help="train steps between evaluations (0: none, and no eval compile: "
                           "training success alone)")
  parser.add_argument("--budget-s", type=float, default=480.0,
                      help="seconds from the start after which the last method stops training")
  parser.add_argument("--train-s", type=float,
                      help="seconds of training per method (default: an equal share of what is "
                           "left of --budget-s): implementations compared over the same time")
  parser.add_argument("--final-eval-s", type=float, default=15.0,
                      help="seconds of each method's share kept back for its final evaluation")
  parser.add_argument("--out", default=os.environ.get("OUT", "runs/gpu_check"),
                      help="folder of gpu_check.jsonl (default: $OUT)")
  args = parser.parse_args(argv)
  start = time.perf_counter()
  try:
    todo = configs(args.methods, args.set, args.scale, args.seed, args.backend)
  except ValueError as e:
    parser.error(str(e))  # one line, exit 2
  log = Log(pathlib.Path(args.out) / "gpu_check.jsonl")
  log("versions", **versions())

  runs = [(f"{method}/{impl}" if impl else method, impl, config)
          for impl in (args.impls or [None]) for method, config in todo.items()]
  for i, (method, impl, config) in enumerate(runs):
    with bench.mjx_impl(impl):  # the envs built inside
      started = start_method(log, method, config, evaluations=args.eval_every > 0)
      if args.physics and i == 0:
        try:  # a failure here must not cost the training below its share of the call
          measure_physics(log, config.tasks, args.batches, args.settings, args.physics_steps,
                          args.threads)
        except Exception as e:  # noqa: BLE001 - reported, then the check goes on
          log("physics_failed", error=f"{type(e).__name__}: {e}"[:2000])
    left = args.budget_s - (time.perf_counter() - start)
    share = min(args.train_s, left) if args.train_s else left / (len(runs) - i)
    train_method(log, method, *started, share, args.eval_every, args.final_eval_s)
  log("done", total_s=time.perf_counter() - start)


if __name__ == "__main__":
  main()
