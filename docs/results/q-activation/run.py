"""A row of Tables I and II with one change: the discriminator reads back the activation the
decoder read, tanh(z), instead of the head's unbounded z (`discriminator_target:
activation`; docs/notes/2026-12-04-i-discriminator.md, "The discriminator against exploration"):

  python docs/results/q-activation/run.py ROW SEED OUT [B]   # e.g. ROW discosyn6-l-reward-set2

The config is the committed record's, docs/results/paper/ROW-seedSEED/config.json, with
that one field changed (and the synergy count, where B is given); OUT gets its own
config.json.
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
  if len(sys.argv) > 4:
    config = config.replace(n_synergies=int(sys.argv[4]))
  loop.train(config.replace(discriminator_target="activation"), out,
             make_trainer=tasks.trainer, progress=False)
