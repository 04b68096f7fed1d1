"""A row of the tables as a composed config: `config_for(method, task_set)` builds the config
a Method names (experiments/method.py) from its parts, on a task set at the `cpu` size (a
scale's sizes replace it), so that `Method.of(config_for(m, s)) == m`. The planner
(paper.py) builds every row it trains from here; `discosyn train --preset` keeps its named
configs (presets.py).

A row that reads its space from a file (a fitted PCA or autoencoder space, a `-matched`
decoder, a space used on other tasks) is not composed here: the planner makes that file
first and gives it to the row's config."""

from __future__ import annotations

import re

from discosyn_jax import decoders
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.experiments import presets
from discosyn_jax.experiments.method import FLOOR_TAG, SWITCH_TAGS, Method
from discosyn_jax.tasks import TASK_SETS

_FLOOR = re.compile(re.escape(FLOOR_TAG) + r"(?P<floor>\d+(?:\.\d+)?)")
_SWITCHES = {part: field for field, part in SWITCH_TAGS.items()}


def tagged(method: Method) -> dict:
  """The config fields a method's tag parts name: each task's own noise, its bonus capped,
  a floor on the heads' z std (Method.of writes them)."""
  fields = {}
  for part in method.tag:
    floor = _FLOOR.fullmatch(part)
    if part in _SWITCHES:
      fields[_SWITCHES[part]] = True
    elif floor:
      fields["z_std_floor"] = float(floor["floor"])
    else:
      raise BadInput(f"{method}: its part {part!r} names no config field (a study's own label)")
  return fields


def config_for(method: Method | str, task_set: str, **fields) -> TrainConfig:
  """The config of row `method` (a Method or its name) on `task_set`; `fields` replace the
  `cpu` size's (a scale's sizes; `tasks` for a set of a plan's own), before a residual's
  ramp and start, in train steps in the name, become shares of the run."""
  method = Method.parse(method) if isinstance(method, str) else method
  if method.family in ("PCA", "AE") or method.control == "matched" or method.reuse:
    raise BadInput(f"{method}: a row whose space is read from a file; the planner makes the file "
                   "first (paper.py)")
  if task_set not in TASK_SETS and "tasks" not in fields:
    raise BadInput(f"unknown task set {task_set!r}; sets: {', '.join(TASK_SETS)}")
  base = TrainConfig(**{"tasks": tuple(TASK_SETS.get(task_set, ())), **presets.CPU_RUN, **fields})
  if method.family == "PPO":
    return base.replace(**presets.PPO, **tagged(method)).validate()
  if (method.family == "Random" and method.start) or (method.family == "Prior" and not method.start):
    raise BadInput(f"{method}: a frozen decoder is Prior at a prior's start, Random at a random one")
  fields = dict(n_synergies=method.synergies, decoder=decoders.by_letter(method.decoder).name,
                squash_z=method.control != "zfree", decoder_init=method.start or "random",
                freeze_decoder=method.family in ("Random", "Prior"), own_synergies=method.own,
                **tagged(method))
  if method.decay:
    fields.update(decoder_weight_decay=method.decay, decoder_weight_decay_steps=method.decay_steps)
  if method.residual:
    steps = base.steps
    fields.update(residual=method.residual.cap, residual_ramp=method.residual.ramp / steps,
                  residual_start=method.residual.start / steps)
  return base.replace(**fields).validate()
