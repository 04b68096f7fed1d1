"""How far each set #2 decoder's space is from the actions with which full-action PPO solves
the weight pull and the dice, at the run's start and at its end, beside when the run found
the task: the planted bed's measurement (the shared space's reach, studies/planted_lag.py)
on set #2.

  python -m studies.solving_reach [--ppo RUN] [--actions FILE] [RECORD_FOLDER ...]

1. The solving actions: the deterministic actions of a trained full-action PPO run of set #2
   (--ppo, a run folder with its checkpoint), per task, saved to --actions (a small npz);
   with --actions alone they are read back, no PPO run needed.
2. For every finished linear set #2 run in the record folders: the distance from each of
   those actions to the decoder's reachable set {W u + c : u in [-1, 1]^b} (z is bounded,
   the decoder reads tanh z), the RMS per actuator of the box-bounded least squares, before
   the env's clip (a distance the clip can only shorten), averaged over the actions; for the
   decoder the run started from (the reward prior's, rebuilt from the run's config, or the
   run's own `decoder_from`) and the one it ended with (decoder.npz). Beside it: when the
   run found the task (evaluated success 0.8) and its end (finding_lag).

A decoder that reaches PPO's solving actions at its start gives the heads a space where the
task can be found; one that does not must move there first, paid by a task it has not found.
One PPO policy's actions are one way to solve the task, not the only one: a far distance
says the space does not hold PPO's way, not that no way is in it. Results:
docs/notes/2026-12-06-d-unpaid-task.md."""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

RECORDS = ("docs/results/paper", "docs/results/residual-set2", "docs/results/confirm-late-residual")
TASKS = ("weight_pull", "dice")
SAMPLES = 300  # actions per task the distance is averaged over


def solving_actions(ppo_run: pathlib.Path, episodes: int = 16) -> dict[str, np.ndarray]:
  """{task: (n, action_size)} the applied actions of a trained full-action run's
  deterministic policy, as the sequential baselines' fit collects them."""
  import jax

  from discosyn_jax.synergies import fitting
  from discosyn_jax import assemble
  from discosyn_jax.training import evaluation

  trainer, state = assemble.load(ppo_run)
  if not trainer.config.kind.full_action:
    raise ValueError(f"{ppo_run} is not a full-action run")
  key = jax.random.PRNGKey(trainer.config.seed + 2)
  return fitting.applied_actions(evaluation.rollouts(trainer, state.params, state.normalizers,
                                                     key, episodes))


def distance(kernel: np.ndarray, bias: np.ndarray, actions: np.ndarray) -> float:
  """The mean over `actions` of the RMS per actuator from each to {kernel.T u + bias :
  u in [-1, 1]^b}."""
  from scipy.optimize import lsq_linear

  out = [lsq_linear(kernel.T, a - bias, bounds=(-1.0, 1.0)).fun for a in actions]
  return float(np.mean([np.sqrt(np.mean(r ** 2)) for r in out]))


def starting_decoder(run) -> dict | None:
  """The run's starting decoder parameters as decoder.npz holds them ('synergies.kernel',
  'synergies.bias'), rebuilt from its config; None where it started random (the same
  draw for every row of a seed: networks.random_decoder)."""
  from discosyn_jax.agent import networks
  from discosyn_jax.synergies import start
  from discosyn_jax import assemble

  trainer = assemble.trainer(run.config.replace(steps=1))
  params = start.starting_decoder(trainer)
  if params is None:
    params = networks.random_decoder(run.config, trainer.action_size)
  return {"synergies.kernel": np.asarray(params["synergies"]["kernel"]),
          "synergies.bias": np.asarray(params["synergies"]["bias"])}


def linear_runs(folders) -> list:
  from studies.finding_lag import runs

  return [r for r in runs(folders, "set2")
          if r.config.kind.linear and r.config.squash_z and not r.config.freeze_decoder
          and (r.path / "decoder.npz").is_file()]


def table(found: list, actions: dict[str, np.ndarray], tasks=TASKS, seed: int = 0) -> list[str]:
  from studies.finding_lag import found_at, in_order

  rng = np.random.default_rng(seed)
  picked = {t: actions[t][rng.choice(len(actions[t]), min(SAMPLES, len(actions[t])), replace=False)]
            for t in tasks}
  lines = ["| method | seed | " + " | ".join(f"{t}: found | end | start -> end distance" for t in tasks)
           + " |", "|---|---|" + "---|---|---|" * len(tasks)]
  starts: dict = {}
  for method, run in in_order(found):
    with np.load(run.path / "decoder.npz") as data:
      end = {k: data[k] for k in ("synergies.kernel", "synergies.bias")}
    key = (run.config.seed, run.config.n_synergies, run.config.decoder_init)
    if key not in starts:
      starts[key] = starting_decoder(run)
    begin = starts[key]
    cells = []
    for t in tasks:
      at = found_at(run, t)
      cells.append(f"{'-' if at is None else f'{at / 1e6:.2f} M'} | {run.final[f'{t}/success']:.2f} | "
                   f"{distance(begin['synergies.kernel'], begin['synergies.bias'], picked[t]):.3f} -> "
                   f"{distance(end['synergies.kernel'], end['synergies.bias'], picked[t]):.3f}")
    lines.append(f"| {method} | {run.seed} | " + " | ".join(cells) + " |")
  return lines


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("folders", nargs="*", type=pathlib.Path,
                      default=[pathlib.Path(p) for p in RECORDS])
  parser.add_argument("--ppo", type=pathlib.Path,
                      help="a trained full-action set #2 run (with its checkpoint) to take the "
                           "solving actions from")
  parser.add_argument("--actions", type=pathlib.Path, required=True,
                      help="the solving actions' npz: written from --ppo, else read")
  parser.add_argument("--tasks", nargs="+", default=list(TASKS))
  args = parser.parse_args(argv)
  if args.ppo:
    actions = solving_actions(args.ppo)
    args.actions.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.actions, **{t: a.astype(np.float16) for t, a in actions.items()})
  elif not args.actions.is_file():
    parser.error(f"no solving actions at {args.actions}: give --ppo RUN to collect them")
  with np.load(args.actions) as data:
    actions = {t: data[t].astype(np.float64) for t in data.files}
  missing = [t for t in args.tasks if t not in actions]
  if missing:
    parser.error(f"{args.actions} holds no actions of {', '.join(missing)}")
  print("\n".join(table(linear_runs(args.folders), actions, args.tasks)))


if __name__ == "__main__":
  main()
