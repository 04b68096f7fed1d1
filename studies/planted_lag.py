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
  residual      a full-action residual beside the synergies, ramped to 0.3 over the first
                half of the run (the `-residual` presets; agent/residual.py)
  residual-late the same held at 0 for the first third, ramped over a sixth (`-residual-late`)
  ppo           full-action PPO (the paper's control) at the same size

then finding_lag's table of the found task and a dense one: when each run first reaches 0.8,
and over the first WINDOW env steps what it was paid, its head's entropy and the bonus.

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
            "floor": {"z_std_floor": FLOOR}, "residual": presets.RESIDUAL,
            "residual-late": presets.RESIDUAL_LATE,
            "ppo": None}
# each variant's part of its method's name (experiments/method.py)
NAMED = {"default": {}, "q-activation": {"tag": ("qact",)}, "zfree": {"control": "zfree"},
         "no-bonus": {"tag": ("alpha2=0",)}, "floor": {}, "residual": {}, "residual-late": {},
         "ppo": {}}  # Method.of names the floor and the residual
SETS = ("planted_found", "planted_reach", "planted_far")


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
  args = parser.parse_args(argv)

  from studies.finding_lag import print_tables, runs
  from studies.residual_transfer import train_row

  from discosyn_jax.tasks import TASK_SETS

  for name, config, meta in configs(args.variants, args.seeds, args.steps, args.set):
    print(f"[{name}] train", flush=True)
    train_row(args.out, name, config, meta)
  print_tables(runs([args.out], args.set), [TASK_SETS[args.set][-1], "planted0"], args.window)


if __name__ == "__main__":
  main()
