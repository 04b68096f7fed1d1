"""The figures of `discosyn report` (report.py): evaluation curves per method with their
spread over seeds, the decoder's overlap curves, performance profiles with their intervals,
and the t-SNE of the z a DiscoSyn policy picks (the paper's Fig. 6)."""

from __future__ import annotations

import pathlib

import numpy as np

from discosyn_jax.experiments.report_runs import LabelledRun, order


def curves(runs: list[LabelledRun], path: pathlib.Path, title: str, metric: str = "success") -> pathlib.Path:
  """Evaluation `metric` against env steps of each task: a panel per task, a line per
  method (mean over seeds; the band spans the seeds)."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt

  task_names = list(dict.fromkeys(t for r in runs for t in r.config.tasks))
  fig, axes = plt.subplots(1, len(task_names), figsize=(max(6, 4 * len(task_names)), 3.4),
                           squeeze=False)
  for ax, task in zip(axes[0], task_names):
    for method in order({r.method for r in runs if task in r.config.tasks}):
      group = [r for r in runs if r.method == method and task in r.config.tasks and r.evaluations]
      if group:
        _band(ax, method, [[(r.per_task_env_steps(row), row.get(f"{task}/{metric}", np.nan))
                            for row in r.evaluations] for r in group])
    ax.set_title(task)
    ax.set_xlabel("env steps of the task")
    ax.set_ylabel(f"evaluation {metric}")
    ax.grid(alpha=0.3)
  return _save(fig, axes, title, path)


def _save(fig, axes, title: str, path: pathlib.Path) -> pathlib.Path:
  """A figure of panels with the legend in the last one, written to `path` and closed."""
  import matplotlib.pyplot as plt

  axes[0][-1].legend(fontsize=7, loc="best")
  fig.suptitle(title)
  fig.tight_layout()
  fig.savefig(path, dpi=90)
  plt.close(fig)
  return path


def _band(ax, label: str, series: list[list[tuple[float, float]]]) -> None:
  """A line of the mean over runs of (x, y) series, and a band spanning the runs."""
  steps = sorted({x for one in series for x, _ in one})
  table = np.full((len(series), len(steps)), np.nan)
  for i, one in enumerate(series):
    for x, y in one:
      table[i, steps.index(x)] = y
  line, = ax.plot(steps, np.nanmean(table, axis=0), label=f"{label} [{len(series)}]")
  if len(series) > 1:
    ax.fill_between(steps, np.nanmin(table, axis=0), np.nanmax(table, axis=0),
                    color=line.get_color(), alpha=0.2)


def overlap_curves(runs: list[LabelledRun], path: pathlib.Path, title: str) -> pathlib.Path | None:
  """The decoder's overlap with the planted span and with its own start against env steps
  of each task, as logged every train step: a line per method (mean over seeds, band)."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt

  from discosyn_jax.synergies import diagnostics

  rows = {r.path: [row for row in r.metrics if "decoder/change" in row]
          for r in runs}
  titles = {"decoder/overlap_planted": "with the planted span",
            "decoder/overlap_start": "with its own start"}
  keys = [k for k in titles if any(k in row for r in runs for row in rows[r.path])]
  if not keys:
    return None
  fig, axes = plt.subplots(1, len(keys), figsize=(5 * len(keys), 3.4), squeeze=False)
  for ax, key in zip(axes[0], keys):
    for method in order({r.method for r in runs}):
      group = [r for r in runs if r.method == method and any(key in row for row in rows[r.path])]
      if group:
        _band(ax, method, [[(r.per_task_env_steps(row), row[key]) for row in rows[r.path]
                            if key in row] for r in group])
    b = runs[0].config.n_synergies
    ax.axhline(diagnostics.chance_overlap(b, b, runs[0].action_size), color="gray", ls=":", label="chance")
    ax.set_title(f"overlap {titles[key]}")
    ax.set_xlabel("env steps of the task")
    ax.set_ylabel("overlap")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
  return _save(fig, axes, title, path)


def profiles(scores: dict[str, dict[str, np.ndarray]], path: pathlib.Path, title: str,
             levels: np.ndarray = np.linspace(0, 1, 101)) -> pathlib.Path:
  """Performance profiles (intervals.py) of {method: {score: runs x tasks}}: a panel per
  score, a line per method of the fraction of its runs x tasks above each success level,
  the band its 95 % interval."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt

  from discosyn_jax.experiments import intervals

  names = list(next(iter(scores.values())))
  fig, axes = plt.subplots(1, len(names), figsize=(5 * len(names), 3.6), squeeze=False)
  for method, by_score in scores.items():
    found = intervals.performance_profile(by_score, levels)
    for ax, name in zip(axes[0], names):
      profile, low, high = found[name]
      line, = ax.plot(levels, profile, drawstyle="steps-post",
                      label=f"{method} [{len(by_score[name])}]")
      ax.fill_between(levels, low, high, step="post", color=line.get_color(), alpha=0.15)
  for ax, name in zip(axes[0], names):
    ax.set_title(name)
    ax.set_xlabel("success level")
    ax.set_ylabel("fraction of runs x tasks above it")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
  return _save(fig, axes, title, path)


def tsne(run: LabelledRun, path: pathlib.Path) -> pathlib.Path:
  """t-SNE of the z the deterministic policy picks on each task (the paper's Fig. 6): the
  run's z samples (record.z_of: its z.npz, else drawn from its checkpoint)."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt
  from sklearn.manifold import TSNE

  from discosyn_jax.experiments import record

  samples = record.z_of(run.path)
  zs = [samples[task] for task in run.config.tasks]
  labels = [n for n, z in enumerate(zs) for _ in range(len(z))]
  z = np.concatenate(zs)
  embedded = TSNE(n_components=2, perplexity=min(30.0, len(z) / 4), random_state=0).fit_transform(z)
  fig, ax = plt.subplots(figsize=(5, 4.5))
  labels = np.array(labels)
  for n, task in enumerate(run.config.tasks):
    ax.scatter(*embedded[labels == n].T, s=4, label=task)
  ax.legend(markerscale=3, fontsize=8)
  ax.set_title(f"t-SNE of z: {run.method} on {run.task_set} (seed {run.seed})")
  ax.set_xticks([])
  ax.set_yticks([])
  fig.tight_layout()
  fig.savefig(path, dpi=90)
  plt.close(fig)
  return path


# -- the report ------------------------------------------------------------------
