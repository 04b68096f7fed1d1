"""Training curves of one run, as PNGs: what the loop draws at the end of a run and what a
report puts side by side.

  success.png  per-task success over env steps: deterministic evaluations (eval.jsonl, dots)
               and the training episodes (metrics.jsonl, thin lines)
  return.png   the same for the episode return
  losses.png   the PPO losses, entropies, discriminator loss and gradient norm
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

from discosyn_jax import config as config_lib  # noqa: E402
from discosyn_jax.checks import BadInput  # noqa: E402
from discosyn_jax.run import folder, layout  # noqa: E402

# losses.png panels: one line per task (columns `task/name`), or one shared column
_PER_TASK = ("policy_loss", "value_loss", "entropy_z")
_SHARED = ("loss", "entropy_a", "discriminator_loss", "grad_norm")


def _read(run_dir: pathlib.Path) -> tuple[config_lib.TrainConfig, list[dict], list[dict]]:
  """(config, metrics rows, eval rows) of a run directory that has trained (folder.read)."""
  run_dir = pathlib.Path(run_dir)
  if not (run_dir / layout.CONFIG_FILE).is_file():
    raise BadInput(f"{run_dir} holds no run (no config.json)")
  run = folder.read(run_dir)
  if not run.metrics:
    raise BadInput(f"{run_dir} holds no training steps yet")
  return run.config, run.metrics, run.evaluations


def series(rows: list[dict], column: str) -> tuple[list[float], list[float]]:
  """(env steps, values) of the rows that have `column`."""
  kept = [r for r in rows if column in r]
  return [r["env_steps"] for r in kept], [r[column] for r in kept]


def _per_task_figure(config, metrics, evals, what: str, path: pathlib.Path, title: str) -> None:
  fig, ax = plt.subplots(figsize=(7, 4))
  for n, task in enumerate(config.tasks):
    colour = f"C{n % 10}"
    x, y = series(metrics, f"{task}/{what}")
    if x:
      ax.plot(x, y, color=colour, alpha=0.35, linewidth=1)
    x, y = series(evals, f"{task}/{what}")
    ax.plot(x, y, "o-", color=colour, markersize=3, label=task)
  ax.set_xlabel("env steps")
  ax.set_ylabel(what)
  ax.set_title(f"{title} (dots: deterministic evaluations, thin: training episodes)", fontsize=9)
  ax.legend(fontsize=8)
  ax.grid(alpha=0.3)
  fig.tight_layout()
  fig.savefig(path, dpi=100)
  plt.close(fig)


def _losses_figure(config, metrics, path: pathlib.Path, title: str) -> None:
  panels = [(name, [(task, f"{task}/{name}") for task in config.tasks]) for name in _PER_TASK]
  panels += [(name, [(None, name)]) for name in _SHARED]
  panels = [(name, cols) for name, cols in panels if any(series(metrics, c)[0] for _, c in cols)]
  columns = 3
  rows = -(-len(panels) // columns)
  fig, axes = plt.subplots(rows, columns, figsize=(11, 2.8 * rows), squeeze=False)
  for ax, (name, cols) in zip(axes.flat, panels):
    for n, (task, column) in enumerate(cols):
      x, y = series(metrics, column)
      ax.plot(x, y, color=f"C{n % 10}", linewidth=1, label=task)
    ax.set_title(name, fontsize=9)
    ax.set_xlabel("env steps", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)
    if len(cols) > 1:
      ax.legend(fontsize=7)
  for ax in list(axes.flat)[len(panels):]:
    ax.set_visible(False)
  fig.suptitle(title, fontsize=10)
  fig.tight_layout()
  fig.savefig(path, dpi=100)
  plt.close(fig)


CURVES = ("success.png", "return.png", "losses.png")  # what run_curves draws, in RUN/plots


def run_curves(run_dir: pathlib.Path, out_dir: pathlib.Path) -> list[pathlib.Path]:
  """Write success.png, return.png and losses.png of the run in `run_dir` into `out_dir`
  (replacing them: they are drawn from the run's logs); return their paths."""
  run_dir, out_dir = pathlib.Path(run_dir), pathlib.Path(out_dir)
  config, metrics, evals = _read(run_dir)
  out_dir.mkdir(parents=True, exist_ok=True)
  name = run_dir.resolve().name
  paths = [out_dir / curve for curve in CURVES]
  _per_task_figure(config, metrics, evals, "success", paths[0], f"{name}: success")
  _per_task_figure(config, metrics, evals, "return", paths[1], f"{name}: return")
  _losses_figure(config, metrics, paths[2], f"{name}: losses")
  return paths
