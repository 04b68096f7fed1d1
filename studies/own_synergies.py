"""Does a task find a direction outside the shared span when it has synergies of its own
(`own_synergies`: task n acts through the b shared directions and k of its own)?

  planted  the planted test bed with targets partly outside the span (`planted_out0-3`,
           residual_planted's tasks: each task's own unit direction w_n, orthogonal to the
           span, carries `outside`^2 / (2 + `outside`^2) of its target's power): the
           `planted` preset's run (DiscoSyn3-L from a random decoder, 2.05 M env steps of four
           tasks) once per variant and seed, one run at a time; a table of final success,
           success over the curve, final return, the decoder's overlap with the planted span
           and, with own synergies, how much of each task's own direction w_n its own
           synergies span at the end (the squared cosine of w_n to span(W_n), mean over the
           tasks; chance k / 17)
  set2     set #2 (`cpu` size, fast physics) with the confirmation's row of each task's own
           noise with the capped bonus (DiscoSyn6-L-reward-tasknoise-bonuscap), and k own
           synergies per task, on the seeds given (exploratory: the rows it is read beside
           have committed records of these seeds)

  python -m studies.own_synergies planted [--seeds 0 1] [--variants ...] [--out DIR]
  python -m studies.own_synergies set2 --seeds 3 [--own 3] [--out DIR]

A planted run is 1-2 min on 2 busy cores; a set #2 run 55-70 min two side by side."""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs/results"
PLAN = RESULTS / "confirm-task-noise-bonus-cap/plan.json"  # its set #2 rows
PRESET = "planted-disco3-linear"
OUTSIDE = 0.5  # residual_planted's: 11 % of each target's power off the span
VARIANTS = {  # name: the fields changed from the planted preset
    "default": {},
    "own1": {"own_synergies": 1},
    "own2": {"own_synergies": 2},
    "residual0.3": {"residual": 0.3},  # the planted bed's strongest residual (notes)
}


def planted_config(variant: str, seed: int, task_names, steps: int | None = None):
  from discosyn_jax.experiments import presets

  config = presets.preset(PRESET).replace(tasks=tuple(task_names), seed=seed, **VARIANTS[variant])
  return (config if steps is None else config.replace(steps=steps)).validate()


def own_found(run_dir: pathlib.Path, outside: float) -> float | None:
  """The mean over the tasks of cos^2(w_n, span(W_n)): how much of task n's own direction
  outside the planted span its own synergies hold at the end (None without them)."""
  from discosyn_jax.run import checkpoints
  from discosyn_jax.tasks import planted

  arrays = checkpoints.read_arrays(run_dir / "final", "params.params.")
  if "own_synergies" not in arrays:
    return None
  values = []
  for n, own in enumerate(arrays["own_synergies"]):
    q = np.linalg.qr(own.T.astype(np.float64))[0]  # (actions, k)
    w = planted.outside_direction(planted.default_config(index=n, outside=outside))
    values.append(float(np.sum((q.T @ w) ** 2)))
  return float(np.mean(values))


def train_planted(args) -> list[tuple[str, int, pathlib.Path]]:
  from discosyn_jax.tasks import assemble
  from studies.residual_planted import register_outside_tasks

  names = register_outside_tasks(args.outside)
  done = []
  for variant in args.variants:
    for seed in args.seeds:
      run_dir = args.out / f"{variant}-outside{args.outside:g}-seed{seed}"
      if not (run_dir / "closing.json").exists():  # one run at a time; a finished one is kept
        assemble.train(planted_config(variant, seed, names, args.steps), run_dir,
                       force=run_dir.exists(), progress=False, log=lambda *a: None)
      done.append((variant, seed, run_dir))
  return done


def measured(run_dir: pathlib.Path, outside: float) -> dict:
  """What the table reads beyond the run's evaluations, kept in RUN/study.json while the
  run's logs and final checkpoint are there (the committed record keeps config.json,
  eval.jsonl, closing.json and study.json): the overlap with the planted span at the end
  and how much of w_n the own synergies hold."""
  import json

  from studies.residual_planted import summary

  kept = run_dir / "study.json"
  if not kept.is_file():
    kept.write_text(json.dumps({"overlap": summary(run_dir)["overlap"],
                                "own_found": own_found(run_dir, outside)}) + "\n")
  return json.loads(kept.read_text())


def planted_table(done, outside: float) -> str:
  import discosyn_jax as ds

  lines = ["| variant | seed | a task acts in | final success | success over the curve | "
           "final return | overlap with the span | own synergies hold w_n |",
           "|---|---|---|---|---|---|---|---|"]
  mean = lambda values: sum(values) / len(values)
  for variant, seed, run_dir in done:
    run, more = ds.read_run(run_dir), measured(run_dir, outside)
    config, last = run.config, run.evaluations[-1]
    found = more["own_found"]
    lines.append(f"| {variant} | {seed} | {config.n_synergies + config.own_synergies} | "
                 f"{mean(list(run.success.values())):.2f} | {run.mean_success:.2f} | "
                 f"{mean([last[f'{t}/return'] for t in config.tasks]):.2f} | "
                 f"{more['overlap']:.2f} | {'-' if found is None else f'{found:.2f}'} |")
  return "\n".join(lines)


def set2_config(seed: int, own: int, steps: int | None = None):
  """The confirmation plan's set #2 row of each task's own noise with the capped bonus, with
  `own` synergies of each task's own."""
  from discosyn_jax.experiments import confirm

  plan = confirm.load(PLAN)
  config = next(row.config for row in plan.rows if row.name == "set2-tncap")
  config = config.replace(seed=seed, own_synergies=own)
  return (config if steps is None else config.replace(steps=steps)).validate()


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  sub = parser.add_subparsers(dest="part", required=True)
  p = sub.add_parser("planted")
  p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/own-planted"))
  p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
  p.add_argument("--outside", type=float, default=OUTSIDE)
  p.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
  p.add_argument("--steps", type=int, help="train steps (default: the preset's)")
  p = sub.add_parser("set2")
  p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/own-set2"))
  p.add_argument("--seeds", type=int, nargs="+", required=True)
  p.add_argument("--own", type=int, default=3, help="own synergies per task (default: %(default)s)")
  p.add_argument("--steps", type=int, help="train steps (default: the plan row's)")
  args = parser.parse_args(argv)

  if args.part == "planted":
    print(planted_table(train_planted(args), args.outside))
    return
  from discosyn_jax.experiments import method as method_lib
  from discosyn_jax.tasks import assemble

  for seed in args.seeds:
    config = set2_config(seed, args.own, args.steps)
    name = method_lib.Method.of(config).name.lower()
    run_dir = args.out / f"{name}-set2-seed{seed}"
    assemble.train(config, run_dir, resume=run_dir.exists(), progress=False)


if __name__ == "__main__":
  main()
