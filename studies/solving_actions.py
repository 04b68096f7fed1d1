"""How much of a solving policy's actions each linear synergy space holds.

  python studies/solving_actions.py runs/paper --set set2

FOLDER is the runs of `discosyn experiment`: `discosyn keep` leaves the fits' actions.npz
(1 MB a seed) out of its records, so a kept folder has none.

For each seed whose fit of full-action PPO's actions is in FOLDER
(synergies-<set>-seed<n>/actions.npz: the trained policy's actions, per task) and each
linear decoder of that set and seed there (learned, frozen or fitted): the overlap of its
span with the span of PCA-k of those actions (diagnostics.overlap; chance max(p, q) / 20),
and per task the share of the policy's action variance about the task's mean action that
the span holds. A space a solving policy works in holds most of it; a row can still solve
a task in a span of its own, so this reads where the rows' spaces are, not whether they
work. Results: docs/notes/2026-12-04-e-solving-actions.md.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from discosyn_jax import decoders  # noqa: E402
from discosyn_jax.synergies import diagnostics, fitting, priors  # noqa: E402


def variance_share(actions: np.ndarray, span: np.ndarray) -> float:
  """The share of the actions' variance (about their mean) inside span(span's columns)."""
  centred = actions - actions.mean(axis=0)
  return priors.captured(span, centred.T @ centred)


def linear_spans(folder: pathlib.Path, task_set: str, seed: int) -> dict[str, np.ndarray]:
  """{method: (actions, b) basis} of the linear decoders of `task_set` and `seed` in folder."""
  spans = {}
  for run in sorted(folder.glob(f"*-{task_set}-seed{seed}")):
    try:
      meta, params = fitting.read(run)
    except ValueError:  # a full-action run, or a folder that holds no decoder
      continue
    if not decoders.kind(meta["decoder"]).linear:
      continue
    info = json.loads((run / "experiment.json").read_text()) if (
        run / "experiment.json").is_file() else {}
    if info.get("experiment") in ("transfer", "sparse"):  # a decoder of a row, frozen again
      continue
    spans[info.get("method", run.name)] = fitting.basis(meta, params)
  return spans


def table(folder: pathlib.Path, task_set: str, k: int) -> str:
  lines = []
  for kept in sorted(folder.glob(f"synergies-{task_set}-seed*/actions.npz")):
    seed = int(kept.parent.name.rsplit("seed", 1)[1])
    with np.load(kept) as data:
      actions = {t: data[t] for t in data.files}
    # PCA-k of the policy's actions, as the PCA rows fit it
    top = fitting.fit_pca(np.concatenate(list(actions.values())), k)[0]["synergies"]["kernel"].T
    if not lines:
      lines += [f"| seed | row | overlap with PCA{k} of PPO's actions | "
                + " | ".join(actions) + " |", "|---" * (len(actions) + 3) + "|"]
    for method, span in linear_spans(folder, task_set, seed).items():
      shares = " | ".join(f"{variance_share(a, span):.2f}" for a in actions.values())
      chance = diagnostics.chance_overlap(k, span.shape[1], span.shape[0])
      lines.append(f"| {seed} | {method} | {float(diagnostics.overlap(top, span)):.2f} "
                   f"(chance {chance:.2f}) | {shares} |")
  if not lines:
    raise ValueError(f"{folder} holds no synergies-{task_set}-seed<n>/actions.npz")
  return "\n".join(lines)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("folder", type=pathlib.Path, help="runs of `discosyn experiment` or kept")
  parser.add_argument("--set", default="set2", help="the task set (its fits' folders)")
  parser.add_argument("--k", type=int, default=4, help="directions of the policy's actions")
  args = parser.parse_args(argv)
  try:
    print(table(args.folder, args.set, args.k))
  except ValueError as e:
    parser.error(str(e))


if __name__ == "__main__":
  main()
