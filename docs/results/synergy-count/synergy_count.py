"""How many synergies each task set needs by the reward prior's own measure (no training):
for b = 3..12, the share of each task's reward metric that the reward prior's b directions
keep (physics_prior: reward response, each task its share), and the smallest b at which
every task keeps >= 80 % (SAR's rule of 80 % of the variance accounted for).

  python docs/results/synergy-count/synergy_count.py set1 set2   # ~2 min on 2 idle cores
"""

import sys

import discosyn_jax

discosyn_jax.setup_jax()

import tasks  # noqa: E402
from discosyn_jax.synergies import physics_prior as pp  # noqa: E402
from experiments import presets  # noqa: E402

for set_name in sys.argv[1:]:
  config = presets.preset(f"{set_name}-disco4-linear")
  metrics = {name: pp.metric(env, "reward") for name, env in zip(config.tasks, tasks.make_envs(config))}
  enough = None
  for b in range(3, 13):
    directions = pp.pool(list(metrics.values()), b, "share")
    kept = {name: pp.captured(directions, m) for name, m in metrics.items()}
    if enough is None and min(kept.values()) >= 0.8:
      enough = b
    print(f"{set_name} b={b:2d}: " + "  ".join(f"{n} {v:.2f}" for n, v in kept.items())
          + f"  (least {min(kept.values()):.2f})")
  print(f"{set_name}: every task keeps >= 80 % of its reward metric from b = {enough}")
