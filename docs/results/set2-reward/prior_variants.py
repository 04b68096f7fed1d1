"""How much of each task's rewarded response each candidate prior keeps (no training).

  python docs/results/set2-reward/prior_variants.py set2 6   # ~90 s on 2 cores

For each task of the set's `cpu`-scale runs (the fast physics): its response metrics
(physics_prior.metric: the objects' velocities, and the task's reward), then, for every
response x pooling, the prior's b directions and the share of each task's metrics they keep;
last, the share of each task's scripted motion (its deviation from its mean; the dice has
no script of its own and gets the valves' sweep) inside each prior.
"""

import sys

import numpy as np

import discosyn_jax

discosyn_jax.setup_jax()

import tasks  # noqa: E402
from discosyn_jax.env import scripted  # noqa: E402
from discosyn_jax.synergies import physics_prior as pp  # noqa: E402
from experiments import presets  # noqa: E402

set_name, b = sys.argv[1], int(sys.argv[2])
config = presets.preset(f"{set_name}-disco{b}-linear")
envs = tasks.make_envs(config)
metrics = {(response, name): pp.metric(env, response)
           for response in pp.RESPONSES for name, env in zip(config.tasks, envs)}
for (response, name), m in metrics.items():
  print(f"{response:8s} {name:12s} top-{b} eigenvalues (trace 1): "
        f"{np.sort(np.linalg.eigvalsh(m))[::-1][:b].round(3)}")
print(f"best {b} directions for the task alone, share of its reward metric:",
      {n: round(float(np.sort(np.linalg.eigvalsh(metrics['reward', n]))[::-1][:b].sum()), 3)
       for n in config.tasks})
priors = {f"{r}+{p}": pp.pool([metrics[r, n] for n in config.tasks], b, p)
          for r in pp.RESPONSES for p in pp.POOLINGS}
for label, directions in priors.items():
  kept = {kind: {n: round(pp.captured(directions, metrics[kind, n]), 3) for n in config.tasks}
          for kind in ("reward", "objects")}
  print(f"{label}: reward kept {kept['reward']}  objects kept {kept['objects']}")
print("scripted motions' variance (about their mean) inside each prior:")
for label, directions in priors.items():
  q, _ = np.linalg.qr(directions)
  row = {}
  for name, env in zip(config.tasks, envs):
    deviation = np.asarray(scripted.for_task(name, env.episode_length, env.dt))
    deviation = deviation - deviation.mean(0)
    row[name] = round(float(np.sum((deviation @ q) ** 2) / np.sum(deviation ** 2)), 3)
  print(f"  {label}: {row}")
