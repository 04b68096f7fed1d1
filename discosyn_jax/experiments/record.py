"""A finished run's record: the small files that stand for it once its checkpoints are gone,
so that a folder of records (docs/results/...) continues an experiment (`discosyn experiment
NAME --out FOLDER` retrains none of the runs it holds) and regenerates its report.

A Train step of discosyn_jax/experiments/paper.py ends by writing, beside config.json, eval.jsonl,
closing.json (the closing evaluation, written by the loop) and experiment.json:
  decoder.npz       the decoder at the end as a synergy file (fitting.save), runs with a
                    linear or mlp decoder: what a matched control and a frozen transfer
                    read, and the report's learned subspaces
  z.npz             the z the deterministic policy picks on each task (float16, a few
                    thousand points), runs whose decoder is learned (DiscoSyn): the t-SNE
  metrics.jsonl.xz  the rows of metrics.jsonl a record keeps (run/logs.py `kept`), compressed
A fit folder's record is its explained_variance.json and synergy files (its actions.npz,
megabytes, is left out: no later step reads it); a matched control's decoder folder holds
its decoder.npz. `keep` copies the records of a folder of runs (`discosyn keep OUT DEST`);
what it leaves out (checkpoints/, final/, plots/, tb/, metrics.jsonl) is never needed again.
"""

from __future__ import annotations

import json
import pathlib
import shutil

import numpy as np

from discosyn_jax import atomic, config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.run import folder, layout, logs

FIT_FILE = "explained_variance.json"  # in a folder of synergy files: what the fits explain
ACTIONS_FILE = "actions.npz"  # a fit's training data: not part of its record
Z_EPISODES, Z_POINTS = 8, 2000  # deterministic episodes per task, z samples in all


def files(config: TrainConfig) -> tuple[str, ...]:
  """The files of the record of a finished run of `config`."""
  names = (layout.CONFIG_FILE, layout.EVAL_FILE, layout.EXPERIMENT_FILE,
           layout.METRICS_FILE + logs.ARCHIVED)
  if config.closing_episodes:  # runs made before the closing evaluation have none (0)
    names += (layout.CLOSING_FILE,)
  if not config.kind.full_action:
    names += (layout.DECODER_FILE,) + (() if config.freeze_decoder else (layout.Z_FILE,))
  return names


def write(run_dir: pathlib.Path, trainer, state) -> None:
  """Write the record's own files of the run in `run_dir` from its final `state`."""
  import jax

  from discosyn_jax.synergies import fitting

  run_dir, config = pathlib.Path(run_dir), trainer.config
  logs.archive(run_dir / layout.METRICS_FILE, config.unroll_length)
  if config.closing_episodes and not (run_dir / layout.CLOSING_FILE).is_file():
    from discosyn_jax.training import loop  # a run stopped between its end and its closing

    loop.write_closing(trainer, state, run_dir)
  if config.kind.full_action:
    return
  decoder = jax.device_get(state.params["params"]["synergy_decoder"])
  meta = fitting.meta_of(config)  # its start too: it names the frozen rows it feeds
  fitting.save(run_dir / layout.DECODER_FILE, decoder, meta, step=int(state.step),
               decoder_init=meta["decoder_init"])
  if not config.freeze_decoder:
    z = {task: samples.astype(np.float16) for task, samples in z_samples(trainer, state).items()}
    with atomic.replacing(run_dir / layout.Z_FILE, ".npz") as tmp:  # written whole, then renamed
      np.savez(tmp, **z)


def z_samples(trainer, state, episodes: int = Z_EPISODES,
              points: int = Z_POINTS) -> dict[str, np.ndarray]:
  """{task: (samples, b)}: the z the deterministic policy picks at the running steps of
  `episodes` episodes per task (a fixed key), `points` in all, an equal share per task."""
  import jax

  from discosyn_jax.training import evaluation

  rollouts = evaluation.rollouts(trainer, state.params, state.normalizers,
                                 jax.random.PRNGKey(0), episodes)
  rng = np.random.default_rng(0)
  out = {}
  for task, traj in rollouts.items():
    z = np.asarray(traj["z"])[np.asarray(traj["alive"]) > 0]
    out[task] = z[rng.permutation(len(z))[:points // len(rollouts)]]
  return out


def has_z(run_dir: pathlib.Path) -> bool:
  """Whether `z_of` can give the run's z samples: its z.npz, or a checkpoint to draw them
  from (a folder of logs alone has neither)."""
  from discosyn_jax.run import checkpoints

  run_dir = pathlib.Path(run_dir)
  return (run_dir / layout.Z_FILE).is_file() or bool(checkpoints.candidates(run_dir))


def z_of(run_dir: pathlib.Path) -> dict[str, np.ndarray]:
  """The z samples of a run: its z.npz (its final state's), else drawn from its newest
  checkpoint (a run made before records, or by `discosyn train`)."""
  path = pathlib.Path(run_dir) / layout.Z_FILE
  if path.is_file():
    with np.load(path) as data:
      return {task: data[task].astype(np.float32) for task in data.files}
  from discosyn_jax import assemble

  trainer, state = assemble.load(run_dir)
  return z_samples(trainer, state)


def saved_config(run_dir: pathlib.Path) -> TrainConfig:
  """The config of the run in `run_dir`, its `decoder_from` read from the run's sibling
  folder of that name where one holds the file: an experiment's folder that moved (kept,
  cloned) still names its own steps' decoders (fitted spaces, matched and transferred
  decoders), wherever it was made."""
  run_dir = pathlib.Path(run_dir)
  config = config_lib.load(run_dir / layout.CONFIG_FILE)
  if not config.decoder_from:
    return config
  sibling = _sibling(run_dir, config.decoder_from)
  return config.replace(decoder_from=str(sibling)) if sibling else config


def _sibling(run_dir: pathlib.Path, decoder_from: str) -> pathlib.Path | None:
  """Where `decoder_from` (<folder>/<file>, or a run's <folder>, wherever it was made) lies
  beside `run_dir`, if it does; never for a shipped synergy name (one part)."""
  source = pathlib.Path(decoder_from)
  if len(source.parts) < 2:
    return None
  beside = pathlib.Path(run_dir).resolve().parent
  sibling = (beside / source.parent.name / source.name if source.suffix == ".npz"
             else beside / source.name)
  return sibling if sibling.exists() else None


def complete(run_dir: pathlib.Path, config: TrainConfig) -> bool:
  """Whether `run_dir` holds every file of the record of a run of `config`, its last
  evaluation at the config's final step."""
  run_dir = pathlib.Path(run_dir)
  if not all((run_dir / name).is_file() for name in files(config)):
    return False
  return folder.finished(run_dir, config, logs.read_log(run_dir / layout.EVAL_FILE))


def finished(run_dir: pathlib.Path, config: TrainConfig) -> bool:
  """Whether `run_dir` holds a finished run of `config` (but for what is done after the run,
  config.AFTER_THE_RUN): its final checkpoint, or its record alone (a folder of records,
  checkpoints never kept)."""
  run_dir = pathlib.Path(run_dir)
  if not (run_dir / layout.CONFIG_FILE).is_file():
    return False
  saved = saved_config(run_dir)
  if not config_lib.same_run(saved, config):
    return False
  return (run_dir / layout.FINAL).is_dir() or complete(run_dir, saved)


def _record_of(folder: pathlib.Path) -> list[str] | None:
  """The files of the record in `folder` ([] for a run without one: unfinished, or
  finished before records were written); None for a folder of something else."""
  if (folder / layout.CONFIG_FILE).is_file():
    config = saved_config(folder)
    return list(files(config)) if complete(folder, config) else []
  if (folder / FIT_FILE).is_file():
    return [FIT_FILE] + sorted(p.name for p in folder.glob("*.npz") if p.name != ACTIONS_FILE)
  if (folder / layout.DECODER_FILE).is_file():  # a matched control's decoder
    return [layout.DECODER_FILE]
  return None


def _relative_decoder_from(folder: pathlib.Path, config_file: pathlib.Path) -> None:
  """A kept config names a decoder of its own experiment by its sibling folder
  (../<folder>/<file>), not by the path of the machine it was made on (saved_config finds
  it there)."""
  fields = json.loads(config_file.read_text())
  if not fields.get("decoder_from"):
    return
  sibling = _sibling(folder, fields["decoder_from"])
  if sibling:
    fields["decoder_from"] = "../" + sibling.relative_to(folder.resolve().parent).as_posix()
    atomic.write_text(config_file, json.dumps(fields, indent=1))


def keep(out: pathlib.Path, dest: pathlib.Path, log=print) -> list[pathlib.Path]:
  """Copy the record of every step folder of `out` into a folder of the same name in
  `dest` (files there replaced); return those folders. A run without a record is named
  and left out."""
  out, dest = pathlib.Path(out), pathlib.Path(dest)
  if not out.is_dir():
    raise BadInput(f"{out} is not a folder")
  if dest.resolve() == out.resolve() or out.resolve() in dest.resolve().parents:
    raise BadInput(f"{dest} is {out} or inside it: keep the records in another folder")
  kept = []
  for folder in sorted(p for p in out.iterdir() if p.is_dir()):
    names = _record_of(folder)
    if names is None:
      continue
    if not names:
      log(f"{folder.name}: unfinished, or finished before its record was written (running "
          "its experiment again writes it); left out")
      continue
    target = dest / folder.name
    target.mkdir(parents=True, exist_ok=True)
    for name in names:
      shutil.copyfile(folder / name, target / name)
    if layout.CONFIG_FILE in names:
      _relative_decoder_from(folder, target / layout.CONFIG_FILE)
    kept.append(target)
  if not kept:
    raise BadInput(f"{out} holds no finished run or fit to keep")
  return kept
