"""Named training configs: `discosyn train --preset NAME`; flags replace single fields.

Each preset is a TrainConfig (discosyn_jax/config.py), so a typo in a field name fails at
import, not in the middle of a run. The paper's runs (Tables I and II) are here by name,
`<set>-disco<b>-<linear|mlp>` and `<set>-ppo`; discosyn_jax/experiments/paper.py runs them at a scale.
The linear DiscoSyn presets start every seed's decoder from the reward prior (one synergy
space from every seed: set #1 5 seeds, set #2 3 seeds, docs/notes/2026-12-03-a-reward-prior.md);
`<set>-disco<b>-linear-reward`, `-objects` (the objects prior) and `-paper` (the paper's
random start) name each start on every set.
"""

from __future__ import annotations

from discosyn_jax import decoders
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.tasks import TASK_SETS

# the size of a run on a CPU: a run of set1-disco3-linear took 55 min for 10 M env steps on 2 cores
CPU_RUN = dict(num_envs=128, unroll_length=20, num_minibatches=8, update_epochs=4, steps=2000,
               eval_every=50, eval_envs=64, checkpoint_every=100)
# the test bed: pure JAX, 2.05 M env steps of four tasks in 2-3 min on 2 busy cores (2026-12-02)
PLANTED_RUN = dict(num_envs=64, unroll_length=20, num_minibatches=4, update_epochs=4, steps=400,
                   eval_every=25, eval_envs=64, checkpoint_every=100)
# a tie-breaker: a decoder weight decay that falls from 8 to nothing over 200 train
# steps (the test bed: one span from every seed, docs/notes/2026-12-02-a-planted-test-bed.md); `<preset>-decay`
DECAY = dict(decoder_weight_decay=8.0, decoder_weight_decay_steps=200)
DECAYED = "-decay"
# where `discosyn experiment discosyn-<set>` runs it beside the paper's update: on the hand
# (set #1) it shrank the decoder until the valves failed (success 0.06-0.16), so there it is
# a preset to try, not a row of the tables
DECAYED_SETS = ("planted", "planted_slack")
# the objects prior: every seed's decoder starts in the subspace of the actions that
# move the objects most (discosyn_jax/synergies/priors.py); `<preset>-objects`, and
# `<preset>-paper` for the paper's random start
OBJECTS = dict(decoder_init="objects")
OBJECTS_SUFFIX, PAPER = "-objects", "-paper"
# the task-aware prior, the start of every linear DiscoSyn preset: the actions that change what
# each task rewards, each task its share of the directions in turn (priors.py); as
# good as the objects prior on set #1 (5 seeds) and set #2 (3 seeds), and it keeps what
# a task rewards where other motion is larger; `<preset>-reward`
REWARD = dict(decoder_init="reward")
REWARDED = "-reward"
# a residual beside the synergies (discosyn_jax/agent/residual.py): each head's full-action
# correction, its weight ramped from 0 to a cap of 0.3 over the first half of the run (set #1's
# `cpu`-scale run: 150 of 300 train steps, set #2's: 600 of 1,200); on the planted test bed
# with targets partly outside the span it took success from 0.40-0.47 to 0.94-0.96 (2 seeds,
# docs/notes/2026-12-05-c-residual-planted.md); `<preset>-residual`, a row to measure, not the default
RESIDUAL_CAP = 0.3
RESIDUAL = dict(residual=RESIDUAL_CAP, residual_ramp=0.5)
RESIDUAL_SUFFIX = "-residual"
# the late schedule: the residual held at 0 for the first third of the run, then ramped in
# over a sixth (set #2's `cpu` scale: 400 and 200 of 1,200 train steps, chosen on seeds 0-1
# of set #2, docs/notes/2026-12-05-g-residual-more.md); `<preset>-residual-late`, the row the confirmation plans
# of docs/results/confirm-late-residual/ test on new seeds
RESIDUAL_LATE = dict(residual=RESIDUAL_CAP, residual_start=1 / 3, residual_ramp=1 / 6)
LATE_SUFFIX = "-residual-late"
# full-action PPO: no discriminator, no decoder noise, a smaller initial std on 20 dims
PPO = dict(decoder="identity", n_synergies=20, alpha2=0.0, alpha3=0.0, init_z_std=0.5,
           squash_z=False)
# the paper's start, random, named where a preset keeps it (TrainConfig's own is the prior)
RANDOM = dict(decoder_init="random")
# TrainConfig's own start (the reward prior for a linear decoder learned from scratch), which
# follows the decoder a `replace` gives: the default rows' (`quickstart`, `<set>-disco<b>-linear`)
DEFAULT_START = dict(decoder_init="auto")

PRESETS: dict[str, TrainConfig] = {
    # the README's main job: synergies (one shared linear decoder, b = 3, z bounded) on two
    # valves, 2-3 minutes on 2 idle cores (819 k env steps), long enough to turn them
    # (docs/notes/2026-11-29-b-quickstart.md: 3 seeds)
    "quickstart": TrainConfig(tasks=("valve2", "valve3"), n_synergies=3, decoder="linear",
                              squash_z=True, **DEFAULT_START, num_envs=128, unroll_length=20, num_minibatches=8,
                              update_epochs=4, steps=160, eval_every=20, eval_envs=32,
                              checkpoint_every=80),
    # independent full-action PPO on one valve (the paper's first baseline stage)
    "valve3-ppo": TrainConfig(tasks=("valve3",), **PPO, **CPU_RUN),
}
# DiscoSyn<b>-L / -NL on the paper's sets (Table I: b = 3, 4; Table II: b = 4, 6), and the
# independent full-action policies the sequential baselines start from
for _set, _sizes in (("set1", (3, 4)), ("set2", (4, 6))):
  _tasks = TASK_SETS[_set]
  PRESETS[f"{_set}-ppo"] = TrainConfig(tasks=_tasks, **PPO, **CPU_RUN)
  for _b in _sizes:
    for _kind in (decoders.LINEAR.name, decoders.MLP.name):
      # z bounded (squash_z): the decoder then has to learn its synergies; with z free a
      # random decoder did as well (docs/notes/2026-11-29-a-decoder-does-not-learn.md)
      PRESETS[f"{_set}-disco{_b}-{_kind}"] = TrainConfig(tasks=_tasks, n_synergies=_b,
                                                        decoder=_kind, squash_z=True, **RANDOM,
                                                        **CPU_RUN)
    _paper = PRESETS[f"{_set}-disco{_b}-linear"]
    PRESETS[f"{_set}-disco{_b}-linear{PAPER}"] = _paper
    PRESETS[f"{_set}-disco{_b}-linear{OBJECTS_SUFFIX}"] = _paper.replace(**OBJECTS)
    PRESETS[f"{_set}-disco{_b}-linear{REWARDED}"] = _paper.replace(**REWARD)
    PRESETS[f"{_set}-disco{_b}-linear{DECAYED}"] = _paper.replace(**DECAY)
    PRESETS[f"{_set}-disco{_b}-linear"] = _paper.replace(**DEFAULT_START)
    PRESETS[f"{_set}-disco{_b}-linear{RESIDUAL_SUFFIX}"] = _paper.replace(**REWARD, **RESIDUAL)
    PRESETS[f"{_set}-disco{_b}-linear{LATE_SUFFIX}"] = _paper.replace(**REWARD, **RESIDUAL_LATE)

# DiscoSyn3 on the planted test bed: (a) one adequate subspace, (b) many, (c) as (a) with one
# task that pays only once it is found: near its target (planted_found), for an excursion
# (planted_reach, planted_far: further)
for _set in ("planted", "planted_slack", "planted_found", "planted_reach", "planted_far"):
  _tasks = TASK_SETS[_set]
  for _kind in (decoders.LINEAR.name, decoders.MLP.name):
    PRESETS[f"{_set}-disco3-{_kind}"] = TrainConfig(tasks=_tasks, n_synergies=3, decoder=_kind,
                                                   squash_z=True, **RANDOM, **PLANTED_RUN)
  PRESETS[f"{_set}-disco3-linear{DECAYED}"] = PRESETS[f"{_set}-disco3-linear"].replace(**DECAY)
  PRESETS[f"{_set}-disco3-linear{RESIDUAL_SUFFIX}"] = PRESETS[f"{_set}-disco3-linear"].replace(
      **RESIDUAL)


def preset(name: str) -> TrainConfig:
  if name not in PRESETS:
    raise BadInput(f"unknown preset {name!r}; presets: {', '.join(PRESETS)}")
  return PRESETS[name]
