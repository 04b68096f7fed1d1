"""The residual on a task set of one's own (docs/examples/own_set/: press a button, rake a
puck 9 cm), beside the rows of docs/results/own-set-hard/, as a researcher would run them
from Python:

  python docs/results/residual-own-set/run.py {default,zfree,residual,zfree-residual} SEED OUT_DIR

default: DiscoSyn3-L-reward; zfree: Random3-L-zfree (a frozen random decoder, z free);
residual / zfree-residual: the same with the residual of `set1-disco3-linear-residual`
(cap 0.3), ramped in over the first half of the run's 100 train steps, as set #1's is over
its 300. The sizes are own-set-hard's: the `cpu` scale's, 100 train steps (256 k env steps),
an evaluation every 5. Each run ends by writing its record (decoder, z) and experiment.json.
"""

import importlib.util
import json
import pathlib
import sys

import discosyn_jax as ds
from discosyn_jax.experiments import paper, record

FILE = "docs/examples/own_set/own_set.py"  # as own-set-hard's configs name it (from the repo)
TASKS = ("Press", "RakeFar")
STEPS = 100
ROWS = {"default": "DiscoSyn3-L-reward", "zfree": "Random3-L-zfree",
        "residual": "DiscoSyn3-L-reward-res0.3r50", "zfree-residual": "Random3-L-zfree-res0.3r50"}


def register() -> None:
  """The tasks under own-set-hard's names (the file's path from the repo), not load_task's
  absolute path: the report matches tasks by name, and a record names no machine's path."""
  spec = importlib.util.spec_from_file_location("own_set", FILE)
  module = sys.modules["own_set"] = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(module)
  for name in TASKS:
    ds.register_task(f"{FILE}:{name}", getattr(module, name))


def config(method: str, seed: int) -> ds.TrainConfig:
  preset = "set1-disco3-linear-residual" if method.endswith("residual") else "set1-disco3-linear"
  base = ds.preset(preset).replace(
      tasks=tuple(f"{FILE}:{name}" for name in TASKS), seed=seed,
      **{**paper.SCALES["cpu"].train, "steps": STEPS, "eval_every": 5})
  if method.endswith("residual"):
    base = base.replace(residual_ramp=0.5)
  if method.startswith("zfree"):
    base = base.replace(freeze_decoder=True, squash_z=False, decoder_init="random")
  return base.validate()


if __name__ == "__main__":
  method, seed, out = sys.argv[1], int(sys.argv[2]), pathlib.Path(sys.argv[3])
  register()
  done = ds.train(config(method, seed), out, progress=False, resume=(out / "config.json").exists())
  record.write(out, done["trainer"], done["state"])
  (out / "experiment.json").write_text(json.dumps(
      {"experiment": "discosyn-own-set", "method": ROWS[method], "set": "+".join(TASKS),
       "seed": seed, "scale": f"cpu sizes, {STEPS} train steps"}, indent=1) + "\n")
