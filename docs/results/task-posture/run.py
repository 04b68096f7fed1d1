"""A row of Tables I and II with one change: each task learns its own posture, added to the
shared decoder's mean (`task_posture: true`; docs/notes/2026-12-05-a-task-posture.md, "A posture per task"):

  python docs/results/task-posture/run.py ROW SEED OUT   # e.g. ROW discosyn6-l-reward-set2

The config is the committed record's, docs/results/paper/ROW-seedSEED/config.json, with
that one field changed; OUT gets its own config.json.
"""

import pathlib
import sys

import tasks
from discosyn_jax import config as config_lib
from discosyn_jax.training import loop

RECORDS = pathlib.Path(__file__).resolve().parents[1] / "paper"

if __name__ == "__main__":
  row, seed, out = sys.argv[1], int(sys.argv[2]), pathlib.Path(sys.argv[3])
  config = config_lib.load(RECORDS / f"{row}-seed{seed}" / "config.json")
  loop.train(config.replace(task_posture=True), out, make_trainer=tasks.trainer, progress=False)
