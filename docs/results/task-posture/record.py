"""The record of a task-posture run (docs/notes/2026-12-05-a-task-posture.md, "A posture per task"):

  python docs/results/task-posture/record.py RUN DEST

DEST gets the run's config.json and eval.jsonl, its record's decoder.npz (what a run of
`discosyn experiment` writes at its end), postures.npz ({task: the learned posture c_n,
one value per actuator}) and heads.jsonl.xz (docs/results/q-activation/heads.py --thin).
Then it prints, per task, the posture's norm and its share inside span(W) (the part the
synergies could have reached on their own).
"""

import pathlib
import shutil
import subprocess
import sys

import jax
import numpy as np

import tasks
from discosyn_jax.run import layout
from discosyn_jax.synergies import diagnostics, physics_prior
from discosyn_jax.training import loop
from experiments import record

HEADS = pathlib.Path(__file__).resolve().parents[1] / "q-activation" / "heads.py"

if __name__ == "__main__":
  run, dest = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
  trainer, state = loop.load_trained(run, tasks.trainer)
  record.write(run, trainer, state)
  dest.mkdir(parents=True, exist_ok=True)
  for name in (layout.CONFIG_FILE, layout.EVAL_FILE, layout.DECODER_FILE):
    shutil.copy2(run / name, dest / name)
  params = jax.device_get(state.params["params"])
  postures = np.asarray(params["postures"])
  np.savez(dest / "postures.npz", **dict(zip(trainer.config.tasks, postures)))
  subprocess.run([sys.executable, str(HEADS), "--thin", str(run), str(dest)], check=True)
  basis = np.asarray(diagnostics.synergy_basis(trainer.model, state.params))
  for task, c in zip(trainer.config.tasks, postures):
    inside = physics_prior.captured(basis, np.outer(c, c))  # c's share inside span(W)
    print(f"{task:12s} |c_n| {np.linalg.norm(c):.3f}  max |c_n,i| {np.abs(c).max():.3f}  "
          f"share in span(W) {inside:.2f}")
