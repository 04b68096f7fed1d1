"""What each task's head does while set #2 trains: the z entropy of pi(z|s,n), the
discriminator's log q, and the task's reward per step, averaged over the 50 train steps up
to each of a few steps (docs/notes/2026-12-04-i-discriminator.md, "The discriminator against exploration").

  python docs/results/q-activation/heads.py TASK RUN...     # the table, one row a run
  python docs/results/q-activation/heads.py --thin RUN DEST  # DEST/heads.jsonl.xz

A RUN is a run folder or a record: its metrics.jsonl(.xz), or the heads.jsonl.xz that
--thin keeps of it (those columns alone, where a whole metrics log is more than a
variant's record needs).
"""

import json
import lzma
import pathlib
import sys

import numpy as np

from discosyn_jax.run import layout, logs

THINNED = "heads.jsonl.xz"
COLUMNS = ("entropy_z", "log_q", "bonus", "reward", "success")
STEPS = (100, 300, 600, 900, 1200)


def rows(run: pathlib.Path) -> list[dict]:
  """The run's metrics log (or its archive), else the thinned one --thin kept."""
  got = logs.read_log(run / layout.METRICS_FILE)
  if not got and (run / THINNED).is_file():
    got = logs.read_jsonl(run / THINNED)
  if not got:
    raise SystemExit(f"{run}: no {layout.METRICS_FILE}(.xz) or {THINNED}")
  return got


def thin(run: pathlib.Path, dest: pathlib.Path) -> None:
  kept = [{k: round(v, 4) if isinstance(v, float) else v for k, v in row.items()
           if k == "step" or k.split("/")[-1] in COLUMNS} for row in rows(run)]
  dest.mkdir(parents=True, exist_ok=True)
  with lzma.open(dest / THINNED, "wt") as f:
    f.writelines(json.dumps(row) + "\n" for row in kept)


def table(task: str, runs: list[pathlib.Path]) -> None:
  print(f"| run | " + " | ".join(f"step {s}: H / log q / reward" for s in STEPS) + " |")
  print("|---" * (len(STEPS) + 1) + "|")
  for run in runs:
    got = rows(run)
    cells = []
    for end in STEPS:
      near = [r for r in got if end - 50 < r["step"] <= end]
      cells.append(" / ".join(f"{np.mean([r[f'{task}/{k}'] for r in near]):+.1f}"
                              for k in ("entropy_z", "log_q")) +
                   f" / {np.mean([r[f'{task}/reward'] for r in near]):+.2f}" if near else "-")
    print(f"| {run.parent.name}/{run.name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
  if sys.argv[1] == "--thin":
    thin(pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3]))
  else:
    table(sys.argv[1], [pathlib.Path(p) for p in sys.argv[2:]])
