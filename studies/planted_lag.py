"""Does the discriminator's bonus narrow a head while its task pays nothing, and does that
make the task found later? The cause planted: three dense tasks of the planted span and a
fourth that pays nothing until it is found (discosyn_jax/tasks/planted.py), in two sets:

  planted_found  the fourth pays only once an action lands near its target (`paid_within`):
                 pay for precision
  planted_reach  the fourth pays only for an excursion along its direction (`excursion`):
                 pay for reach, as set #2's weight pull
  planted_far    as planted_reach, further (near the corner of z's box)

Each variant changes one thing of the set's planted preset (DiscoSyn3-L, z bounded, q
reading z), trained on the same seeds:

  default       the preset as it is
  q-activation  q reads back what the decoder read, tanh z (`discriminator_target`)
  zfree         z unbounded: tanh's saturation cannot hide z from q
  no-bonus      alpha2 = 0: no bonus at all (the discriminator still learns)
  floor         each head's z std held at >= 0.7 until its task first pays a rollout
                (`z_std_floor`; 0.7 = 1.06 nat per dimension: in finding_lag's set #2 table
                every head that kept >= 1.0 found the weight pull)
  task-noise    each task's own decoder noise (`task_noise`): the paid tasks narrow their
                own, not the unpaid task's
  task-noise-no-bonus  the same with alpha2 = 0: nothing but its own PPO narrows a task's
                noise
  task-noise-bonus-cap  the same with the bonus: each task's capped at the spread of what
                it pays (`bonus_cap`), none for a task that pays nothing
  residual      a full-action residual beside the synergies, ramped to 0.3 over the first
                half of the run (the `-residual` presets; agent/residual.py)
  residual-late the same held at 0 for the first third, ramped over a sixth (`-residual-late`)
  ppo           full-action PPO (the paper's control) at the same size

then finding_lag's table of the found task and a dense one: when each run first reaches 0.8,
and over the first WINDOW env steps what it was paid, its head's entropy and the bonus. For
an excursion task, also how far each run's decoder reaches along the task's direction at the
end (z at the corners of its box), and, with --starts, the share of the starting policies'
samples that reach the threshold (no training).

  python -m studies.planted_lag [--set planted_found] [--seeds 0 1 2] [--variants ...]
                                [--steps 400] [--out DIR]

Each run is the planted preset's 2.05 M env steps (4 tasks), 2-3 min on 2 busy cores; a
finished run is kept (its record) and read again."""

from __future__ import annotations

import argparse
import pathlib

from discosyn_jax.experiments import presets  # TrainConfigs only, no JAX

FLOOR = 0.7
VARIANTS = {"default": {}, "q-activation": {"discriminator_target": "activation"},
            "zfree": {"squash_z": False}, "no-bonus": {"alpha2": 0.0},
            "floor": {"z_std_floor": FLOOR}, "task-noise": {"task_noise": True},
            "task-noise-no-bonus": {"task_noise": True, "alpha2": 0.0},
            "task-noise-bonus-cap": {"task_noise": True, "bonus_cap": True},
            "residual": presets.RESIDUAL,
            "residual-late": presets.RESIDUAL_LATE,
            "ppo": None}
# each variant's part of its method's name (experiments/method.py)
NAMED = {"default": {}, "q-activation": {"tag": ("qact",)}, "zfree": {"control": "zfree"},
         "no-bonus": {"tag": ("alpha2=0",)}, "floor": {}, "task-noise": {},
         "task-noise-no-bonus": {"tag": ("tasknoise", "alpha2=0")}, "task-noise-bonus-cap": {},
         "residual": {},
         "residual-late": {}, "ppo": {}}  # Method.of names the floor, the noise, the residual
SETS = ("planted_found", "planted_reach", "planted_far")
GOAL_SIZE = 2  # a planted task's observation: its goal in its plane (task_rank)


def configs(variants, seeds, steps: int | None = None, task_set: str = SETS[0]):
  """(folder name, config, experiment.json) of each variant and seed."""
  from discosyn_jax.experiments.method import Method

  base = presets.preset(f"{task_set}-disco3-linear")
  ppo = base.replace(**presets.PPO)  # full-action PPO at the planted run's size
  if steps is not None:
    base, ppo = base.replace(steps=steps), ppo.replace(steps=steps)
  for variant in variants:
    for seed in seeds:
      changed = ppo if VARIANTS[variant] is None else base.replace(**VARIANTS[variant])
      config = changed.replace(seed=seed).validate()
      method = Method.of(config).replace(**NAMED[variant]).name
      yield (f"{method.lower()}-{task_set}-seed{seed}", config,
             {"experiment": "planted-lag", "method": method, "set": task_set,
              "seed": seed, "scale": "planted"})


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("--set", default=SETS[0], choices=SETS)
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
  parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
  parser.add_argument("--steps", type=int, help="train steps (default: the preset's 400)")
  parser.add_argument("--window", type=int, default=250_000,
                      help="env steps of a task over which finding_lag reads paid, H and bonus")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/planted-lag"))
  parser.add_argument("--starts", action="store_true",
                      help="only print how often the starting policies reach the excursion")
  args = parser.parse_args(argv)
  if args.starts:
    print_starts(args.set, args.seeds)
    return

  from studies.finding_lag import print_tables, runs
  from studies.residual_transfer import train_row

  from discosyn_jax.tasks import TASK_SETS

  for name, config, meta in configs(args.variants, args.seeds, args.steps, args.set):
    print(f"[{name}] train", flush=True)
    train_row(args.out, name, config, meta)
  found = runs([args.out], args.set)
  print_tables(found, [TASK_SETS[args.set][-1], "planted0"], args.window)
  print_reach(found, TASK_SETS[args.set][-1])


def _excursion(task: str):
  """(the task's direction, its threshold); None for a task that pays a posture."""
  from discosyn_jax import tasks
  from discosyn_jax.tasks import planted

  env = tasks.make(task)
  if not env.config.excursion:
    return None
  return planted.task_plane(env.config)[:, 0], env.config.excursion


def decoder_reach(decoder: dict, direction) -> float:
  """The most a linear decoder reaches along `direction` with a bounded z (at a corner of
  z's box, tanh z = +-1), its actions clipped to [-1, 1] as the env clips them."""
  import itertools

  import numpy as np

  kernel, bias = decoder["synergies.kernel"], decoder["synergies.bias"]
  corners = np.array(list(itertools.product([-1.0, 1.0], repeat=kernel.shape[0])))
  return float((np.clip(corners @ kernel + bias, -1, 1) @ direction).max())


def print_reach(found: list, task: str) -> None:
  import numpy as np

  from studies.finding_lag import in_order

  excursion = _excursion(task)
  if excursion is None:
    return
  direction, threshold = excursion
  print(f"\n{task}: the decoder's reach along the task's direction at the end (z at a corner "
        f"of its box; the task pays from {threshold:g})\n")
  print("| method | seed | reach | end |")
  print("|---|---|---|---|")
  for method, run in in_order(found):
    file = run.path / "decoder.npz"
    if not run.config.kind.linear or not file.is_file():
      continue
    reach = decoder_reach(dict(np.load(file)), direction)
    print(f"| {method} | {run.seed} | {reach:.2f} | {run.at_end()[f'{task}/success']:.2f} |")


def print_starts(task_set: str, seeds, draws: int = 200_000) -> None:
  """The share of the starting policies' samples (the synergy preset's, PPO's) that reach the
  excursion task's threshold, per seed: how rare a first payment is before any update."""
  import jax
  import jax.numpy as jnp

  from discosyn_jax.agent import networks, policy
  from discosyn_jax.tasks import TASK_SETS

  task = TASK_SETS[task_set][-1]
  excursion = _excursion(task)
  if excursion is None:
    raise SystemExit(f"{task} pays a posture, not an excursion")
  direction, threshold = excursion
  print(f"{task}: the share of the starting policies' samples reaching {threshold:g}")
  for variant in ("default", "ppo"):
    for _, config, meta in configs([variant], seeds, None, task_set):
      model, params = networks.initial_params(config, (GOAL_SIZE,) * len(config.tasks), 20)
      key = jax.random.PRNGKey(1000 + config.seed)
      goals = jax.random.uniform(key, (draws, GOAL_SIZE), minval=-1.0, maxval=1.0)
      draws_ = policy.noise(jax.random.fold_in(key, 1), draws, model.n_synergies, 20)
      _, action, _ = policy.sample(model, params, len(config.tasks) - 1, goals, draws_)
      reach = jnp.clip(action, -1.0, 1.0) @ direction
      print(f"  {meta['method']} seed {config.seed}: {float((reach >= threshold).mean()):.2%}")


if __name__ == "__main__":
  main()
