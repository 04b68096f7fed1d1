"""`discosyn report RUN_DIRS...`: the paper's tables and figures from run folders.

Writes OUT/REPORT.md and PNG figures beside it:
  - tables of solved tasks per task set, in the paper's layout (a row per method, a column
    per task), each cell with the final deterministic success (mean and spread over seeds,
    the number of seeds) and the paper's mark beside it;
  - explained variance of the sequential baselines' PCA / autoencoder fits;
  - training curves (evaluation success against env steps of that task, per method);
  - t-SNE of the z the DiscoSyn policy picks, coloured by task (the paper's Fig. 6);
  - transfer to unseen tasks and the sparse goal valve: curves and steps to the first reward.

"Solved" is: the mean over seeds of the final evaluation's success >= `threshold`.
A run's method and set come from its experiment.json (written by `discosyn experiment`), or
else from its config.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import pathlib
import re
from typing import Any

import numpy as np

from discosyn_jax import config as config_lib
from discosyn_jax import logs
from discosyn_jax.config import TrainConfig

# The paper's Tables I and II (1 = solved, columns in these tasks' order) and its PCA
# explained variance on set #1.
PAPER_TASKS = {"set1": ("valve0", "valve1", "valve2", "valve3"),
               "set2": ("dice", "valve3", "weight_pull", "screw")}
PAPER_SOLVED = {
    "set1": {"PCA4": "0000", "AE4": "1011", "PCA6": "1001", "AE6": "1011", "DiscoSyn3-L": "1111",
             "DiscoSyn3-NL": "1111", "DiscoSyn4-L": "1111", "DiscoSyn4-NL": "1111"},
    "set2": {"PCA4": "0001", "AE4": "1001", "PCA6": "1001", "AE6": "1001", "DiscoSyn4-L": "1100",
             "DiscoSyn4-NL": "1111", "DiscoSyn6-L": "1111", "DiscoSyn6-NL": "1111"},
}
PAPER_PCA_VARIANCE = {"set1": {3: 0.415, 4: 0.508, 6: 0.628}}
METHOD_ORDER = ("PPO", "PCA4", "AE4", "PCA6", "AE6")
for _b in (3, 4, 6):  # each DiscoSyn row above its random-decoder controls
  METHOD_ORDER += tuple(f"{m}{_b}-{k}{c}" for k in ("L", "NL") for m, c in (
      ("DiscoSyn", ""), ("Random", ""), ("Random", "-zfree"), ("Random", "-matched")))
MAIN_EXPERIMENTS = ("discosyn", "baselines")
EXPERIMENT_FILE = "experiment.json"  # in a run folder: experiment, method, set, seed, scale
FIT_FILE = "explained_variance.json"  # in a folder of synergy files: what the fits explain


@dataclasses.dataclass
class Run:
  path: pathlib.Path
  config: TrainConfig
  experiment: str
  method: str
  task_set: str
  seed: int
  evals: list[dict[str, Any]]
  finished: bool
  scale: str | None  # None for a run `discosyn experiment` did not make

  @property
  def main(self) -> bool:
    """A run of the solved tables (DiscoSyn or a baseline), not transfer or sparse."""
    return self.experiment.split("-")[0] in MAIN_EXPERIMENTS or self.experiment == "train"

  @property
  def final(self) -> dict[str, Any]:
    return self.evals[-1] if self.evals else {}

  def per_task_env_steps(self, row) -> int:
    return row["step"] * self.config.num_envs * self.config.unroll_length


def _method_of(config: TrainConfig) -> str:
  from discosyn_jax import synergies

  if config.decoder == "identity":
    return "PPO"
  if not config.decoder_from:
    return synergies.method_name(config)
  try:  # a synergy file knows its method (PCA, AE); a run folder is DiscoSyn's
    return synergies.method_name(synergies.read(config.decoder_from)[0]) + " frozen"
  except ValueError:
    return synergies.method_name(config) + " frozen"


def _set_of(config: TrainConfig) -> str:
  import tasks

  for name, members in tasks.TASK_SETS.items():
    if tuple(members) == tuple(config.tasks):
      return name
  return "+".join(config.tasks)


def load_run(path: pathlib.Path) -> Run:
  from discosyn_jax import checkpoints, runs

  config = config_lib.load(path / "config.json")
  writer = runs.writer_of(path)
  if writer:  # its logs are read as far as they go now
    checkpoints.warn(f"{path} is being written by {writer}: read its logs as they are now")
  meta_file = path / EXPERIMENT_FILE
  meta = json.loads(meta_file.read_text()) if meta_file.is_file() else {}
  evals = logs.read_log(path / logs.EVAL_FILE)
  # logs kept without checkpoints (docs/results) are finished when the last step was evaluated
  finished = (path / "final").is_dir() or bool(evals and evals[-1]["step"] >= config.steps)
  # derived from the config only where experiment.json is silent (_method_of may read a file)
  return Run(path=path, config=config, experiment=meta.get("experiment", "train"),
             method=meta["method"] if "method" in meta else _method_of(config),
             task_set=meta["set"] if "set" in meta else _set_of(config),
             seed=meta.get("seed", config.seed), evals=evals, finished=finished,
             scale=meta.get("scale"))


def find(paths, inside: bool = False) -> tuple[list[Run], list[dict[str, Any]]]:
  """The runs and the synergy fits in `paths` (run folders, fit folders, or folders of them).
  A folder named here must hold one; one found inside (a report, say) may hold none."""
  runs, fits = [], []
  for path in map(pathlib.Path, paths):
    if not path.is_dir():
      raise ValueError(f"{path} is not a folder")
    if (path / "config.json").is_file():
      runs.append(load_run(path))
    elif (path / FIT_FILE).is_file():
      fits.append(json.loads((path / FIT_FILE).read_text()))
    else:
      inner = sorted(p for p in path.iterdir() if p.is_dir())
      found = find(inner, inside=True) if inner else ([], [])
      if not found[0] and not found[1] and not inside:
        raise ValueError(f"{path} holds no run (config.json) and no synergy fit")
      runs += found[0]
      fits += found[1]
  if not inside:
    _one_run_per_seed(runs)
  return runs, fits


def _one_run_per_seed(runs: list[Run]) -> None:
  """Two runs of one method and seed would count as two seeds: name the pair instead."""
  seen = {}
  for run in runs:
    key = (run.experiment, run.task_set, tuple(run.config.tasks), run.method, run.seed)
    if key in seen:
      raise ValueError(f"{seen[key].path} and {run.path} are both {run.method} seed {run.seed} "
                       f"on {run.task_set}; give the report one of them")
    seen[key] = run


# -- tables ---------------------------------------------------------------------
def _success(runs: list[Run], task: str) -> np.ndarray:
  return np.array([r.final[f"{task}/success"] for r in runs if f"{task}/success" in r.final])


def _cell(values: np.ndarray, threshold: float, paper: str | None) -> str:
  if values.size == 0:
    return "–"
  mean = values.mean()
  mark = "✓" if mean >= threshold else "✗"
  spread = f" ({values.min():.0%}–{values.max():.0%})" if values.size > 1 else ""
  paper_mark = "" if paper is None else f" (paper {'✓' if paper == '1' else '✗'})"
  return f"{mark} {mean:.0%}{spread} [{values.size}]{paper_mark}"


def _mean_over_tasks(group: list[Run], task_names) -> str:
  """Each seed's success averaged over the set's tasks, then the mean (min-max) over seeds:
  the figure issue 13's targets compare."""
  per_seed = np.array([np.mean([r.final[f"{t}/success"] for t in task_names]) for r in group
                       if all(f"{t}/success" in r.final for t in task_names)])
  if per_seed.size == 0:
    return "–"
  spread = f" ({per_seed.min():.0%}–{per_seed.max():.0%})" if per_seed.size > 1 else ""
  return f"{per_seed.mean():.0%}{spread}"


def _order(methods) -> list[str]:
  known = [m for m in METHOD_ORDER if m in methods]
  return known + sorted(set(methods) - set(known))


def solved_tables(runs: list[Run], threshold: float) -> str:
  lines = []
  main = [r for r in runs if r.main]
  for task_set in sorted({r.task_set for r in main}):
    in_set = [r for r in main if r.task_set == task_set]
    task_names = list(in_set[0].config.tasks)
    paper = PAPER_SOLVED.get(task_set, {})
    lines += [f"### {task_set}: tasks solved (success >= {threshold:.0%})", "",
              "| method | " + " | ".join(task_names) + " | mean | solved |",
              "|---" * (len(task_names) + 3) + "|"]
    for method in _order({r.method for r in in_set}):
      group = [r for r in in_set if r.method == method]
      cells, solved = [], 0
      paper_tasks = PAPER_TASKS.get(task_set, ())
      for task in task_names:
        values = _success(group, task)
        mark = (paper[method][paper_tasks.index(task)]
                if method in paper and task in paper_tasks else None)
        cells.append(_cell(values, threshold, mark))
        solved += bool(values.size and values.mean() >= threshold)
      paper_count = (f" (paper {paper[method].count('1')}/4)"
                     if method in paper and set(paper_tasks) == set(task_names) else "")
      unfinished = sum(not r.finished for r in group)
      note = f", {unfinished} unfinished" if unfinished else ""
      lines.append(f"| {method} | " + " | ".join(cells) + f" | {_mean_over_tasks(group, task_names)}"
                   f" | {solved}/{len(task_names)}{paper_count}{note} |")
    lines.append("")
  return "\n".join(lines)


def variance_table(fits: list[dict[str, Any]]) -> str:
  sizes = sorted({int(k) for f in fits for m in ("PCA", "AE") for k in f.get(m, {})})
  lines = ["| set | method | " + " | ".join(f"k = {k}" for k in sizes) + " | samples |",
           "|---" * (len(sizes) + 3) + "|"]
  for task_set in sorted({f["set"] for f in fits}):
    group = [f for f in fits if f["set"] == task_set]
    for method in ("PCA", "AE"):
      cells = []
      for k in sizes:
        values = np.array([f[method][str(k)] for f in group if str(k) in f.get(method, {})])
        cell = "–" if values.size == 0 else f"{values.mean():.1%}" + (
            f" ± {values.std():.1%}" if values.size > 1 else "")
        paper = PAPER_PCA_VARIANCE.get(task_set, {}).get(k) if method == "PCA" else None
        cells.append(cell + (f" (paper {paper:.1%})" if paper is not None else ""))
      samples = ", ".join(str(f["samples"]) for f in group)
      lines.append(f"| {task_set} | {method} | " + " | ".join(cells) + f" | {samples} |")
  lines.append("| any | DiscoSyn | " + " | ".join("100% (by construction)" for _ in sizes) + " | |")
  return "\n".join(lines) + "\n"


def decoder_table(runs: list[Run], last: int = 10) -> str:
  """Is the synergy space learned? Per run with a decoder: its movement from the initial
  decoder at the end (diagnostics.py), the gradient norms of decoder and heads, and the
  discriminator's bonus beside the env's reward per step (means over the last `last` logged
  train steps). A frozen decoder's gradient is computed but never applied: marked so."""
  lines = ["| run | env steps | W change | principal cosines | decoder / heads grad norm "
           "| bonus / reward per step |", "|---|---|---|---|---|---|"]
  for run in sorted(runs, key=lambda r: (r.task_set, r.method, r.seed)):
    rows = [r for r in logs.read_log(run.path / logs.METRICS_FILE) if "decoder/change" in r][-last:]
    if not rows:
      continue
    end = rows[-1]
    cosines = " / ".join(f"{end[f'decoder/cos_{k}']:.3f}"
                         for k in range(1, run.config.n_synergies + 1) if f"decoder/cos_{k}" in end)
    mean = lambda key: float(np.mean([r.get(key, np.nan) for r in rows]))
    tasks = run.config.tasks
    bonus = np.mean([mean(f"{t}/bonus") for t in tasks])
    reward = np.mean([mean(f"{t}/reward") for t in tasks])
    frozen = " (frozen)" if run.config.freeze_decoder else ""
    lines.append(f"| {run.method} {run.task_set} seed {run.seed} | {end['env_steps']:,.0f} | "
                 f"{end['decoder/change']:.1%} | {cosines} | {mean('grad_norm/decoder'):.3g}"
                 f"{frozen} / {mean('grad_norm/heads'):.3g} | {bonus:.3f} / {reward:.3f} |")
  return "\n".join(lines) + "\n" if len(lines) > 2 else ""


def _spread(values) -> str:
  """mean (min–max) [count] of some overlaps; – for none."""
  values = np.asarray(values, float)
  if values.size == 0:
    return "–"
  spread = f" ({values.min():.2f}–{values.max():.2f})" if values.size > 1 else ""
  return f"{values.mean():.2f}{spread} [{values.size}]"


def discovery_table(runs: list[Run]) -> str:
  """Is the synergy space discovered? Per method and set with a decoder: the overlaps
  (diagnostics.py) of the seeds' learned subspaces, pair by pair, beside those of the same
  seeds' initial decoders; each seed's overlap with its own start, and with the planted
  span on planted tasks (both as logged at the run's last step); and the chance level."""
  from discosyn_jax import diagnostics, discovery

  lines = ["| method | set | learned, seed pairs | initial, seed pairs | each seed with its start "
           "| each seed with the planted span | chance |", "|---|---|---|---|---|---|---|"]
  decoders = [r for r in runs if r.config.decoder != "identity"]
  for task_set in sorted({r.task_set for r in decoders}):
    for method in _order({r.method for r in decoders if r.task_set == task_set}):
      group = sorted((r for r in decoders if r.task_set == task_set and r.method == method),
                     key=lambda r: r.seed)
      learned = [b for b in map(discovery.learned_basis, (r.path for r in group)) if b is not None]
      initial = [b for b in map(discovery.initial_basis, (r.config for r in group)) if b is not None]
      ends = [_last_logged(r) for r in group]
      start = [e["decoder/overlap_start"] for e in ends if "decoder/overlap_start" in e]
      planted = [e["decoder/overlap_planted"] for e in ends if "decoder/overlap_planted" in e]
      b = group[0].config.n_synergies
      lines.append(f"| {method} | {task_set} | {_spread(discovery.cross_seed(learned))} | "
                   f"{_spread(discovery.cross_seed(initial))} | {_spread(start)} | "
                   f"{_spread(planted)} | {diagnostics.chance_overlap(b, b):.2f} |")
  return "\n".join(lines) + "\n" if len(lines) > 2 else ""


def _last_logged(run: Run) -> dict[str, Any]:
  """The decoder's figures at the last logged train step of a run ({} if none): the
  overlap with its start derived from the cosines for logs older than that metric."""
  rows = [r for r in logs.read_log(run.path / logs.METRICS_FILE) if "decoder/change" in r]
  if not rows:
    return {}
  end = dict(rows[-1])
  cos = [end[f"decoder/cos_{k}"] for k in range(1, run.config.n_synergies + 1)
         if f"decoder/cos_{k}" in end]
  if "decoder/overlap_start" not in end and cos:
    end["decoder/overlap_start"] = float(np.mean(np.square(cos)))
  return end


def first_reward(run: Run, task: str) -> tuple[int, int] | None:
  """(env steps of the task, control steps of each env) until the first non-zero reward of
  `task` in training, or None when none was seen (or the run did not log it)."""
  cfg = run.config
  for row in logs.read_log(run.path / logs.METRICS_FILE):
    t = row.get(f"{task}/first_reward_t")
    if t is not None and t < cfg.unroll_length:
      before = row["step"] - 1  # train steps before the one that saw it
      return (before * cfg.num_envs * cfg.unroll_length + (int(t) + 1) * cfg.num_envs,
              before * cfg.unroll_length + int(t) + 1)
  return None


# -- figures ----------------------------------------------------------------------
def curves(runs: list[Run], path: pathlib.Path, title: str, metric: str = "success") -> pathlib.Path:
  """Evaluation `metric` against env steps of each task: a panel per task, a line per
  method (mean over seeds; the band spans the seeds)."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt

  task_names = list(dict.fromkeys(t for r in runs for t in r.config.tasks))
  fig, axes = plt.subplots(1, len(task_names), figsize=(max(6, 4 * len(task_names)), 3.4),
                           squeeze=False)
  for ax, task in zip(axes[0], task_names):
    for method in _order({r.method for r in runs if task in r.config.tasks}):
      group = [r for r in runs if r.method == method and task in r.config.tasks and r.evals]
      if group:
        _band(ax, method, [[(r.per_task_env_steps(row), row.get(f"{task}/{metric}", np.nan))
                            for row in r.evals] for r in group])
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


def overlap_curves(runs: list[Run], path: pathlib.Path, title: str) -> pathlib.Path | None:
  """The decoder's overlap with the planted span and with its own start against env steps
  of each task, as logged every train step: a line per method (mean over seeds, band)."""
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt

  from discosyn_jax import diagnostics

  rows = {r.path: [row for row in logs.read_log(r.path / logs.METRICS_FILE) if "decoder/change" in row]
          for r in runs}
  titles = {"decoder/overlap_planted": "with the planted span",
            "decoder/overlap_start": "with its own start"}
  keys = [k for k in titles if any(k in row for r in runs for row in rows[r.path])]
  if not keys:
    return None
  fig, axes = plt.subplots(1, len(keys), figsize=(5 * len(keys), 3.4), squeeze=False)
  for ax, key in zip(axes[0], keys):
    for method in _order({r.method for r in runs}):
      group = [r for r in runs if r.method == method and any(key in row for row in rows[r.path])]
      if group:
        _band(ax, method, [[(r.per_task_env_steps(row), row[key]) for row in rows[r.path]
                            if key in row] for r in group])
    b = runs[0].config.n_synergies
    ax.axhline(diagnostics.chance_overlap(b, b), color="gray", ls=":", label="chance")
    ax.set_title(f"overlap {titles[key]}")
    ax.set_xlabel("env steps of the task")
    ax.set_ylabel("overlap")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
  return _save(fig, axes, title, path)


def tsne(run: Run, path: pathlib.Path, episodes: int = 8, points: int = 2000,
         make_trainer=None) -> pathlib.Path:
  """t-SNE of the z the deterministic policy picks on each task (the paper's Fig. 6)."""
  import jax
  import matplotlib

  matplotlib.use("Agg")
  import matplotlib.pyplot as plt
  from sklearn.manifold import TSNE

  from discosyn_jax import loop
  from discosyn_jax.train import Trainer

  trainer, state = loop.load_trained(run.path, make_trainer or Trainer)
  rollouts = trainer.rollouts(state.params, state.normalizers, jax.random.PRNGKey(0), episodes)
  rng = np.random.default_rng(0)
  zs, labels = [], []
  for n, (task, traj) in enumerate(rollouts.items()):
    z = np.asarray(traj["z"])[np.asarray(traj["alive"]) > 0]
    keep = rng.permutation(len(z))[:points // len(rollouts)]
    zs.append(z[keep])
    labels += [n] * len(keep)
  z = np.concatenate(zs)
  embedded = TSNE(n_components=2, perplexity=min(30.0, len(z) / 4), random_state=0).fit_transform(z)
  fig, ax = plt.subplots(figsize=(5, 4.5))
  labels = np.array(labels)
  for n, task in enumerate(rollouts):
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
def write(paths, out: pathlib.Path, threshold: float = 0.8, with_tsne: bool = True,
          force: bool = False, make_trainer=None) -> pathlib.Path:
  """Write OUT/REPORT.md and its figures; return the REPORT.md path."""
  if not 0 < threshold <= 1:
    raise ValueError(f"the success threshold must be in (0, 1], not {threshold}")
  runs, fits = find(paths)
  if not runs and not fits:
    raise ValueError("no runs among the folders given")
  out = pathlib.Path(out)
  report = out / "REPORT.md"
  if report.exists() and not force:
    raise ValueError(f"{out} already holds a report; pass --force to replace it")
  old_figures = set(_figures(report.read_text())) if report.exists() else set()
  out.mkdir(parents=True, exist_ok=True)

  date = datetime.date.today().isoformat()
  lines = [f"# DiscoSyn-JAX report ({date})", "",
           f"{len(runs)} runs and {len(fits)} synergy fits from: "
           + ", ".join(f"`{p}`" for p in paths) + ".",
           f"A task is *solved* when the mean over seeds of the final deterministic evaluation's "
           f"success is at least {threshold:.0%}. Cells: mark, mean success, (min–max "
           "over seeds), [seeds], and the paper's mark (Tables I and II).", ""]
  scales = sorted({r.scale for r in runs if r.scale})
  if scales:
    lines += [f"Scales: {', '.join(scales)}.", ""]

  main = [r for r in runs if r.main]
  if main:
    lines += ["## Tasks solved", "", solved_tables(runs, threshold)]
  if fits:
    lines += ["## Explained variance of the action data", "",
              "PCA and autoencoder fitted to the deterministic actions of the independent "
              "full-action policies of each set (all tasks pooled).", "", variance_table(fits)]

  if main:
    lines += ["## Training curves", ""]
  for task_set in sorted({r.task_set for r in main}):
    group = [r for r in main if r.task_set == task_set]
    name = f"curves-{task_set}.png".replace("+", "_")
    curves(group, out / name, f"{task_set}: deterministic evaluation success")
    lines += [f"![{task_set}]({name})", ""]

  movement = decoder_table(runs)
  if movement:
    lines += ["## Is the synergy space learned?", "",
              "The decoder's synergy basis (linear: W; MLP: its Jacobian at z = 0) against the "
              "one it started from: relative change, and the cosines of the principal angles "
              "between the two subspaces (1: the same subspace). A frozen decoder shows 0 and 1.",
              "", movement]

  discovered = discovery_table(main)
  if discovered:
    lines += ["## Is the synergy space discovered?", "",
              "Overlap of two synergy subspaces: the mean squared cosine of their principal "
              "angles, |Q_i^T Q_j|_F^2 / b (1: the same subspace, 0: orthogonal; two random "
              "b-dim subspaces of the 20 actions: b / 20, the *chance* column). A space the task "
              "set determines has a high overlap between seeds (learned, seed pairs) however "
              "low it was between their random starts (initial); a seed that only turned its "
              "own start keeps a high overlap with it. The planted span: the subspace the "
              "planted tasks' targets lie in (tasks/planted.py). Cells: mean (min–max) [pairs "
              "or seeds]; the learned subspaces need the runs' checkpoints.", "", discovered]
    for task_set in sorted({r.task_set for r in main}):
      name = f"overlap-{task_set}.png".replace("+", "_")
      if overlap_curves([r for r in main if r.task_set == task_set], out / name,
                        f"{task_set}: the decoder's subspace during training"):
        lines += [f"![overlap {task_set}]({name})", ""]

  if with_tsne and any(r.method.startswith("DiscoSyn") for r in main):
    lines += ["## t-SNE of the low-dimensional actions", ""]
    for task_set in sorted({r.task_set for r in main}):
      disco = [r for r in main if r.method.startswith("DiscoSyn") and r.evals]
      disco = [r for r in disco if r.task_set == task_set]
      if not disco:
        continue
      best = max(disco, key=lambda r: (np.mean([r.final.get(f"{t}/success", 0)
                                                for t in r.config.tasks]), -r.seed))
      name = f"tsne-{task_set}.png".replace("+", "_")
      tsne(best, out / name, make_trainer=make_trainer)
      lines += [f"{best.method} (its best-scoring run on {task_set}, `{best.path.name}`):", "",
                f"![t-SNE {task_set}]({name})", ""]

  for experiment, heading in (("transfer", "Transfer to unseen tasks"),
                              ("sparse", "The sparse goal valve")):
    group = [r for r in runs if r.experiment == experiment]
    if not group:
      continue
    lines += [f"## {heading}", "", "| method | task | final success | first reward: env steps "
              "of the task (control steps per env) |", "|---|---|---|---|"]
    for run in sorted(group, key=lambda r: (r.task_set, r.method, r.seed)):
      for task in run.config.tasks:
        success = run.final.get(f"{task}/success")
        first = first_reward(run, task)
        first_text = f"{first[0]:,} ({first[1]:,})" if first else "none seen"
        lines.append(f"| {run.method} (seed {run.seed}) | {task} | "
                     f"{'–' if success is None else f'{success:.0%}'} | {first_text} |")
    name = f"{experiment}.png"
    curves(group, out / name, f"{heading}: deterministic evaluation success")
    lines += ["", f"![{experiment}]({name})", ""]
    if experiment == "sparse":
      curves(group, out / "sparse-return.png", "sparse goal valve: evaluation return", "return")
      lines += ["![sparse return](sparse-return.png)", ""]

  text = "\n".join(lines)
  report.write_text(text)
  # once the new report stands: the old one's figures it did not draw again (--no-tsne, say)
  for name in old_figures - set(_figures(text)):
    (out / name).unlink(missing_ok=True)
  return report


def _figures(report_text: str) -> list[str]:
  """The figure files a REPORT.md links, each beside it."""
  return re.findall(r"\]\(([^)/]+\.png)\)", report_text)
