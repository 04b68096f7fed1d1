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
  python -m studies.own_synergies plan --seeds 16 17 ... [--own 3] --claim TEXT --out PLAN
  python -m studies.own_synergies transfer-plan --seeds 16 ... --claim TEXT --out PLAN
           the plan of transfer with own synergies: the shipped set #1 synergies
           (shadow20-set1) frozen on the unseen pair and on the sparse goal valve, with and
           without 3 synergies of each task's own, beside full-action PPO, every row run on
           the new seeds (TRANSFER_ROWS, TRANSFER_HYPOTHESES)
           the confirmation plan (experiments/confirm.py): the own row on new seeds, set #2's
           full-action PPO, default and each-task's-noise rows named by their committed
           records (COMPARATORS), and the hypotheses of HYPOTHESES

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
  from studies.residual_planted import train_each

  return train_each(args.out, args.variants, args.seeds, args.outside, planted_config, args.steps)


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


# the committed records of set #2's comparator rows, by the confirmation plan's row they are
# the runs of (a record's config must be that row's at its seed: confirm.check_records)
COMPARATORS = {
    "set2-ppo": ["paper/ppo-set2-seed0", "paper/ppo-set2-seed1", "paper/ppo-set2-seed2",
                 *(f"confirm-late-residual/set2-ppo-seed{s}" for s in range(3, 8)),
                 *(f"confirm-task-noise-bonus-cap/set2-ppo-seed{s}" for s in range(11, 16))],
    "set2-default": [*(f"paper/discosyn6-l-reward-set2-seed{s}" for s in range(3)),
                     *(f"confirm-late-residual/set2-default-seed{s}" for s in range(3, 8)),
                     *(f"confirm-task-noise-bonus-cap/set2-default-seed{s}" for s in range(11, 16))],
    "set2-tncap": [*(f"unfound-task/discosyn6-l-reward-tasknoise-bonuscap-set2-seed{s}" for s in (8, 9)),
                   *(f"confirm-task-noise-bonus-cap/set2-tncap-seed{s}" for s in range(11, 16))],
}
ROW = "set2-own"
# (x, y, score, expect, task): each a difference of means with its bootstrap interval
HYPOTHESES = [
    (ROW, "set2-ppo", "curve", "not below", ""),  # the target: not below PPO over the curve
    (ROW, "set2-ppo", "final", "not below", ""),
    (ROW, "set2-ppo", "curve", "not below", "dice"),  # the dice over the curve >= PPO's
    (ROW, "set2-default", "curve", "above", ""),
    (ROW, "set2-tncap", "curve", "above", "dice"),  # what the own directions add: the dice
]


# the transfer plan's rows: `discosyn train` flags at the frozen transfer's size (300 train
# steps x 64 envs x 20 steps a task); PPO with the paper's transfer rows' settings
PAIR, GOAL = "--tasks valve_cylinder valve_cw", "--tasks valve_goal"
TRANSFER_SIZE = "--num-envs 64 --minibatches 4 --steps 300 --eval-every 50 --eval-envs 32"
FROZEN = "--decoder-from shadow20-set1"
TRANSFER_ROWS = {
    "pair-own": f"{PAIR} {FROZEN} --own-synergies 3",
    "pair-frozen": f"{PAIR} {FROZEN}",
    "pair-ppo": f"{PAIR} --preset set1-ppo",
    "goal-own": f"{GOAL} {FROZEN} --own-synergies 3",
    "goal-frozen": f"{GOAL} {FROZEN}",
    "goal-ppo": f"{GOAL} --preset set1-ppo",
}
TRANSFER_HYPOTHESES = [  # (x, y, score, expect, task), each a difference of means
    ("pair-own", "pair-ppo", "final", "not below", "valve_cw"),  # the target
    ("pair-own", "pair-frozen", "curve", "above", "valve_cw"),  # what the own directions add
    ("pair-own", "pair-ppo", "final", "not below", "valve_cylinder"),  # kept
    ("goal-own", "goal-ppo", "final", "not below", ""),
    ("goal-own", "goal-frozen", "final", "above", ""),
]


def transfer_config(row: str, seed: int):
  """The TrainConfig `discosyn train TRANSFER_ROWS[row] TRANSFER_SIZE --seed SEED` builds."""
  from studies.transfer_learned import flags_config

  return flags_config(f"{TRANSFER_ROWS[row]} {TRANSFER_SIZE} --seed {seed}")


def transfer_plan_source(seeds, claim: str, decision: str) -> dict:
  from discosyn_jax.experiments import confirm

  rows = [{"name": row, "seeds": list(seeds),
           "config": confirm.row_fields(transfer_config(row, seeds[0]))} for row in TRANSFER_ROWS]
  hypotheses = [{"x": x, "y": y, "score": score, "expect": expect, "statistic": "difference",
                 **({"task": task} if task else {})}
                for x, y, score, expect, task in TRANSFER_HYPOTHESES]
  return {"name": "own-synergies-transfer", "claim": claim, "final_k": 3, "level_margin": 0.1,
          "rows": rows, "hypotheses": hypotheses, "decision": decision}


def plan_source(seeds, own: int, claim: str, decision: str, plan_dir: pathlib.Path) -> dict:
  """The plan file's JSON: its rows (the own row to run, the comparators by their records,
  relative to `plan_dir`) and hypotheses."""
  import os

  from discosyn_jax.experiments import confirm

  base = confirm.load(PLAN)
  rows = [{"name": ROW, "seeds": list(seeds),
           "config": confirm.row_fields(set2_config(seeds[0], own))}]
  for name, records in COMPARATORS.items():
    paths = [RESULTS / r for r in records]
    seeds_of = [int(p.name.rsplit("seed", 1)[1]) for p in paths]
    rows.append({"name": name, "seeds": seeds_of,
                 "config": confirm.row_fields(base.row(name).config),
                 "records": [os.path.relpath(p, plan_dir) for p in paths]})
  hypotheses = [{"x": x, "y": y, "score": score, "expect": expect, "statistic": "difference",
                 **({"task": task} if task else {})} for x, y, score, expect, task in HYPOTHESES]
  return {"name": "own-synergies", "claim": claim, "final_k": 3, "level_margin": 0.1,
          "rows": rows, "hypotheses": hypotheses, "decision": decision}


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
  for name in ("plan", "transfer-plan"):
    p = sub.add_parser(name)
    p.add_argument("--seeds", type=int, nargs="+", required=True)
    if name == "plan":
      p.add_argument("--own", type=int, default=3)
    p.add_argument("--claim", required=True)
    p.add_argument("--decision", required=True)
    p.add_argument("--out", type=pathlib.Path, required=True, help="the plan file to write")
  args = parser.parse_args(argv)

  if args.part in ("plan", "transfer-plan"):
    import json

    if args.out.exists():
      parser.error(f"{args.out} exists: a committed plan is never rewritten")
    source = (plan_source(args.seeds, args.own, args.claim, args.decision, args.out.parent)
              if args.part == "plan" else
              transfer_plan_source(args.seeds, args.claim, args.decision))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(source, indent=1) + "\n")
    from discosyn_jax.experiments import confirm

    confirm.load(args.out)  # its records are the rows' runs, its hypotheses well formed
    print(args.out)
    return

  if args.part == "planted":
    print(planted_table(train_planted(args), args.outside))
    return
  from discosyn_jax.experiments import method as method_lib
  from studies.residual_transfer import train_row

  for seed in args.seeds:  # each a step of `discosyn experiment`: resumed, kept, its record
    config = set2_config(seed, args.own, args.steps)
    method = method_lib.Method.of(config)
    meta = dict(experiment="own-synergies", method=method.name, set="set2", seed=seed, scale="cpu")
    train_row(args.out, f"{method.name.lower()}-set2-seed{seed}", config, meta)


if __name__ == "__main__":
  main()
