"""Set #1's synergies on set #1's unseen pair (the cylinder valve, the clockwise valve)
learned on rather than frozen, beside a space learned for the pair alone: does the frozen
transfer's clockwise valve (0.38 against full-action PPO's 0.75) come from freezing, or from
what a 3-synergy space reaches on it in 768 k env steps?

  python -m studies.transfer_learned [--rows tuned tuned-tncap scratch] [--seeds 0 1 2]
                                     [--out runs/transfer-learned]

Each row is the `discosyn train` flags below (the frozen transfer's size, `cpu` scale), a
step <row>-seed<n> of OUT that ends with its record, as `discosyn experiment` steps do (a
finished run there is kept, an unfinished one resumed): `discosyn keep OUT DEST` then
`discosyn report DEST`. A row learned on from a decoder copies its source's record beside
it (OUT/<source folder>), so that the kept config names its source by its sibling folder.
  tuned        each seed's set #1 default decoder (SOURCES), learned on with the learned
               rows' bonus and decoder entropy (alpha2 0.01, alpha3 0.001)
  tuned-tncap  the same with each task's own noise and its bonus capped at what it pays
  scratch      DiscoSyn3-L-reward learned on the pair alone, from the pair's reward prior
  own          each seed's set #1 default decoder (SOURCES) frozen, each task with 3 synergies
               of its own beside it (`--own-synergies 3`: the unseen task's own directions,
               started from its reward prior outside the frozen span)
  sparse-own   the same on the sparse goal valve (384 k env steps)
  frozen-from  --source FOLDER: that run's decoder frozen on the pair (the transfer row),
               for a source outside SOURCES (e.g. a confirmation's set #1 run)
  sparse-from  --source FOLDER: that run's decoder frozen on the sparse goal valve (the
               sparse row; 384 k env steps)
With --span FOLDER ...: no training; for every linear decoder in the folders (a run's
decoder.npz, or a source record's) the share of each unseen task's one-step reward metric
(priors.metric, "reward": the directions that change what the task pays in one control
step) that its span holds (priors.captured; the pair's own reward prior beside them).
Results: docs/notes/2026-12-06-f-clockwise-valve.md, docs/results/transfer-learned/."""

from __future__ import annotations

import argparse
import pathlib
import shutil

SOURCES = pathlib.Path("docs/results/paper")  # discosyn3-l-reward-set1-seed<n>: the default
SIZE = "--num-envs 64 --minibatches 4 --steps 300 --eval-every 50"  # the frozen transfer's
PAIR = "--tasks valve_cylinder valve_cw"
LEARNED_ON = "--freeze-decoder no --alpha2 0.01 --alpha3 0.001"
ROWS = {
    "tuned": f"{PAIR} --decoder-from {{source}} {LEARNED_ON}",
    "tuned-tncap": f"{PAIR} --decoder-from {{source}} {LEARNED_ON} --task-noise yes --bonus-cap yes",
    "scratch": f"{PAIR} --preset set1-disco3-linear-reward",
    "own": f"{PAIR} --decoder-from {{source}} --own-synergies 3",
    "sparse-own": "--tasks valve_goal --decoder-from {source} --own-synergies 3",
    "frozen-from": f"{PAIR} --decoder-from {{source}}",
    "sparse-from": "--tasks valve_goal --decoder-from {source}",
}
FROM = ("frozen-from", "sparse-from")  # the rows whose source is --source


def flags_config(flags: str):
  """The TrainConfig `discosyn train FLAGS` builds."""
  from discosyn import cli, commands

  return commands.train_config(cli.build_parser().parse_args(["train", *flags.split()]))


def row_config(row: str, seed: int, source: pathlib.Path | None):
  """The TrainConfig `discosyn train ROWS[row] SIZE --seed SEED` builds."""
  flags = ROWS[row].format(source=source / "decoder.npz" if source else "")
  return flags_config(f"{flags} {SIZE} --seed {seed}")


def beside(out: pathlib.Path, source: pathlib.Path) -> pathlib.Path:
  """The source run's record copied into OUT (once), where a run's config names its decoder
  by that sibling folder, and kept records with it, not by a path of the machine."""
  sibling = out / source.name
  if not sibling.is_dir():
    shutil.copytree(source, sibling, ignore=shutil.ignore_patterns("checkpoints", "final", "tb"))
  return sibling


def train_row(out: pathlib.Path, row: str, seed: int, source: pathlib.Path | None,
              log=print) -> pathlib.Path:
  """Train (or keep, or resume) ROWS[row] for `seed` as the step <row>-seed<n> of OUT."""
  from discosyn_jax.experiments import report_runs
  from studies.residual_transfer import train_row as train_step

  if source is not None:
    source = beside(out, source)
  config = row_config(row, seed, source)
  name = f"{row}-{source.name}" if row in FROM else f"{row}-seed{seed}"
  sparse = row.startswith("sparse")  # named as the paper's rows of these tasks are
  meta = dict(experiment="sparse" if sparse else "transfer", method=report_runs.method_of(config).name,
              set="sparse" if sparse else "unseen-set1", seed=seed, scale="cpu")
  log(f"[{name}]")
  return train_step(out, name, config, meta)


def source_of(row: str, seed: int, given: pathlib.Path | None) -> pathlib.Path | None:
  """The folder whose decoder a row starts from: --source for FROM's rows, each seed's set #1
  default for the tuned rows, none for scratch."""
  if row in FROM:
    return given
  return (SOURCES / f"discosyn3-l-reward-set1-seed{seed}" if row.startswith(("tuned", "own", "sparse-own"))
          else None)


def spans(folders) -> list[str]:
  """The --span table: per decoder, the share of each task's one-step reward metric."""
  from discosyn_jax import config as config_lib, decoders
  from discosyn_jax.synergies import fitting, priors
  from discosyn_jax.tasks import registry

  envs = registry.make_envs(config_lib.TrainConfig(tasks=("valve_cylinder", "valve_cw")).validate())
  metrics = [priors.metric(env, "reward") for env in envs]
  rows = {"the pair's reward prior": priors.basis(envs, 3, "reward", "share")}
  for folder in folders:
    for path in sorted(pathlib.Path(folder).glob("*/decoder.npz")):
      meta, params = fitting.read(path)
      if decoders.kind(meta["decoder"]).linear:
        rows[path.parent.name] = fitting.basis(meta, params)
  lines = ["| decoder | valve_cylinder | valve_cw |", "|---|---|---|"]
  for name, basis in rows.items():
    lines.append(f"| {name} | " + " | ".join(f"{priors.captured(basis, m):.2f}" for m in metrics) + " |")
  return lines


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("--rows", nargs="+", choices=list(ROWS), default=["tuned", "tuned-tncap", "scratch"])
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
  parser.add_argument("--source", type=pathlib.Path,
                      help="frozen-from, sparse-from: the run (or record) folder whose decoder is frozen")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/transfer-learned"))
  parser.add_argument("--span", type=pathlib.Path, nargs="+", metavar="FOLDER",
                      help="no training: the span table of the decoders in these folders")
  args = parser.parse_args(argv)
  if args.span:
    print("\n".join(spans(args.span)))
    return
  if set(FROM) & set(args.rows) and args.source is None:
    parser.error(f"{' and '.join(FROM)} need --source FOLDER")
  args.out.mkdir(parents=True, exist_ok=True)
  for seed in args.seeds:
    for row in args.rows:
      train_row(args.out, row, seed, source_of(row, seed, args.source))


if __name__ == "__main__":
  main()
