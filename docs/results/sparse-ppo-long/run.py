# The exact script of the 2026-12-01 long sparse PPO runs in docs/TRAINING_NOTES.md
# (its input folder was then named table1-cpu-partial).
"""Full-action PPO on the sparse goal valve, the `cpu` sparse experiment's config with 600
train steps (768 k env steps) instead of 300: long enough to show whether PPO's first reward
comes >= 10x later than the learned space's (76 k env steps on the mean of 3 seeds)."""
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[3]))  # the repository
from discosyn_jax import config as config_lib
from discosyn_jax.training import loop
from discosyn_jax.training.train import Trainer

seed, out = int(sys.argv[1]), pathlib.Path(sys.argv[2])
here = pathlib.Path(__file__).parent.parent / "table1-cpu" / f"sparse-ppo-seed{seed}"
config = config_lib.load(here / "config.json").replace(steps=600).validate()
run = out / f"sparse-ppo-seed{seed}"
loop.train(config, run, trainer=Trainer(config), progress=False, log=lambda *a: print(*a, flush=True))
(run / "experiment.json").write_text(json.dumps(
    dict(experiment="sparse", method="PPO", set="sparse", seed=seed, scale="cpu-768k"), indent=1))
