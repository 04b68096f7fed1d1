"""The reward prior against the object-motion prior on set #1 (b = 3) and set #2 (b = 6): the
overlap of their subspaces and the largest actuators of each reward direction (~2 min on 2 cores):

  python docs/results/set2-reward/compare_priors.py
"""

import numpy as np

import discosyn_jax

discosyn_jax.setup_jax()

import tasks  # noqa: E402
from discosyn_jax.env import hands  # noqa: E402
from discosyn_jax.synergies import diagnostics  # noqa: E402
from discosyn_jax.synergies import physics_prior as pp  # noqa: E402
from experiments import presets  # noqa: E402

for set_name, b in (("set1", 3), ("set2", 6)):
  config = presets.preset(f"{set_name}-disco{b}-linear")
  envs = tasks.make_envs(config)
  objects = pp.basis(envs, b, "objects", "trace")
  reward = pp.basis(envs, b, "reward", "share")
  print(set_name, "overlap of the reward and object priors:",
        round(float(diagnostics.overlap(objects, reward)), 3), "chance", b / 20)
  names = [name.split("/")[-1] for name in hands.actuators(config.hand)]
  for k in range(b):
    top = np.argsort(-np.abs(reward[:, k]))[:3]
    print(f"  reward direction {k}: "
          + ", ".join(f"{names[i]} {reward[i, k]:+.2f}" for i in top))
