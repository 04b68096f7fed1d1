# The exact script of the 2026-11-30 ablation in docs/TRAINING_NOTES.md (run folders under runs/ of the repository).
"""Which part of the learned decoder carries DiscoSyn3-L's lead over its random control (seed 0)?
Random3-L's exact config, its decoder frozen at a mix of the random start and the learned end."""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[3]))  # the repository
from discosyn_jax.synergies import fitting
from discosyn_jax.training import loop
from discosyn_jax.training.train import Trainer
from experiments import paper

variant, seed = sys.argv[1], int(sys.argv[2])
O = pathlib.Path("runs/table1-cpu"); A = pathlib.Path("runs/ablation")
meta, start = fitting.read(O / f"random3-l-set1-seed{seed}")
_, end = fitting.read(O / f"discosyn3-l-set1-seed{seed}")
params = {"log_std": start["log_std"], "synergies": dict(start["synergies"])}
if variant == "learned-bias":  # random W, learned c
    params["synergies"]["bias"] = end["synergies"]["bias"]
elif variant == "learned-w":  # learned W, c = 0 (its start)
    params["synergies"]["kernel"] = end["synergies"]["kernel"]
else:
    raise SystemExit(f"unknown variant {variant}")
path = fitting.save(A / f"{variant}-seed{seed}.npz", params, meta)
steps = paper.Planner(O, "cpu", seed).plan("discosyn-set1")
control = next(s for s in steps if s.meta["method"] == "Random3-L")
config = control.config.replace(decoder_from=str(path)).validate()
loop.train(config, A / f"{variant}-seed{seed}", progress=False, trainer=Trainer(config),
           log=lambda *a: print(*a, flush=True))
