"""A task set of one's own (docs/examples/own_set/: press a button, rake a puck) from the
default start, beside its strongest control, as a researcher would run them from Python.

  python docs/results/own-set/run.py {default,zfree} SEED OUT_DIR [TASK ...]

TASK: classes of docs/examples/own_set/own_set.py (default: Press Rake; the harder set,
whose neutral posture solves neither task: Press RakeFar).

default: DiscoSyn3-L-reward (the linear DiscoSyn preset's start: the reward prior, z
bounded); zfree: Random3-L-zfree (a frozen random decoder, z free: the strongest control on
the hand's sets). Both at the `cpu` scale's sizes for 100 train steps (256 k env steps for
two tasks) with an evaluation every 5: at the `cpu` scale's 300 steps, evaluated every 50,
both rows are at 0.94-1.00 from the first evaluation on, and the curve shows nothing.
"""

import json
import pathlib
import sys

import tasks
from discosyn_jax.training import loop
from experiments import paper, presets

HERE = pathlib.Path(__file__).resolve().parent
FILE = HERE.parents[1] / "examples" / "own_set" / "own_set.py"


def config(method: str, seed: int, classes=("Press", "Rake")):
  names = tuple(tasks.load(f"{FILE}:{name}") for name in classes)
  base = presets.preset("set1-disco3-linear").replace(tasks=names, seed=seed,
                                                      **{**paper.SCALES["cpu"].train, "steps": 100, "eval_every": 5})
  if method == "zfree":
    base = base.replace(freeze_decoder=True, squash_z=False, decoder_init="random")
  return base.validate()


if __name__ == "__main__":
  method, seed, out = sys.argv[1], int(sys.argv[2]), pathlib.Path(sys.argv[3])
  classes = tuple(sys.argv[4:]) or ("Press", "Rake")
  loop.train(config(method, seed, classes), out, make_trainer=tasks.trainer, progress=False)
  # the row's name and set for `discosyn report` (its config alone names the control Random3-L)
  row = {"default": "DiscoSyn3-L-reward", "zfree": "Random3-L-zfree"}[method]
  (out / "experiment.json").write_text(json.dumps(
      {"experiment": "discosyn-own-set", "method": row, "set": "+".join(classes), "seed": seed,
       "scale": "cpu sizes, 100 train steps"}, indent=1) + "\n")
