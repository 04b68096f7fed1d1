"""Start-up of a training: seconds to build the Trainer, `init()`, and lower + compile the
train step, with episodes auto-reset freshly (an env reset inside the step) or from a reset
pool (none: on MJX the step then holds no `mjx.forward`). Each measurement runs in a fresh
process with the compile cache off; the variants alternate, so a change of the machine's
load hits both.

  python -m studies.startup_compile --tasks valve3 --backend mjx --repeats 2
  python -m studies.startup_compile --tasks valve2 valve3 --backend mjx --repeats 1
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time


def measure(tasks: list[str], backend: str, pool: bool, num_envs: int) -> dict:
  """One process's figures (runs in the child)."""
  start = time.perf_counter()
  import jax

  from discosyn_jax.config import TrainConfig
  from discosyn_jax import tasks as registry

  config = TrainConfig(tasks=tuple(tasks), backend=backend, reset_pool=pool, num_envs=num_envs,
                       unroll_length=5, num_minibatches=2, update_epochs=1, steps=1)
  trainer = registry.trainer(config)
  built = time.perf_counter()
  state = jax.block_until_ready(trainer.init())
  initialised = time.perf_counter()
  trainer.train_step.lower(state).compile()
  compiled = time.perf_counter()
  return dict(build_s=built - start, init_s=initialised - built, compile_s=compiled - initialised)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=["valve3"])
  parser.add_argument("--backend", default="mjx", choices=["native", "mjx"])
  parser.add_argument("--num-envs", type=int, default=4)
  parser.add_argument("--repeats", type=int, default=2)
  parser.add_argument("--child", choices=["fresh", "pool"], help=argparse.SUPPRESS)
  args = parser.parse_args(argv)
  if args.child:
    print(json.dumps(measure(args.tasks, args.backend, args.child == "pool", args.num_envs)))
    return
  env = dict(os.environ, DISCOSYN_JAX_CACHE="off")
  rows: dict[str, list[dict]] = {"fresh": [], "pool": []}
  print(f"# {' '.join(args.tasks)} on {args.backend}, {args.num_envs} envs per task; "
        f"load {os.getloadavg()[0]:.1f}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
  print("| reset | build s | init s | train-step compile s |\n|---|---|---|---|")
  for _ in range(args.repeats):
    for variant in rows:
      out = subprocess.run([sys.executable, "-m", "studies.startup_compile", "--child", variant,
                            "--backend", args.backend, "--num-envs", str(args.num_envs),
                            "--tasks", *args.tasks], env=env, capture_output=True, text=True,
                           check=True)
      row = json.loads(out.stdout.strip().splitlines()[-1])
      rows[variant].append(row)
      print(f"| {variant} | {row['build_s']:.1f} | {row['init_s']:.1f} | {row['compile_s']:.1f} |",
            flush=True)
  fresh, pool = (statistics.median(r["compile_s"] for r in rows[v]) for v in ("fresh", "pool"))
  print(f"train-step compile, median: pool / fresh = {pool:.1f} / {fresh:.1f} s = {pool / fresh:.2f}")


if __name__ == "__main__":
  main()
