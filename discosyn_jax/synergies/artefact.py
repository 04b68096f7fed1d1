"""Synergies as an artefact: a synergy file that says what it is, the files that ship with the
package, loaded by name, and `Synergies`, what a user holds of one.

A synergy file (fitting.save's .npz: the decoder's parameters and a JSON meta) of FORMAT 2
also names, beside the decoder's layout:
  hand        {"name", "actuators": [in action order], "ctrlrange": [[lo, hi], ...]}: the
              hand whose actions the decoder's output is, mapped from [-1, 1] onto ctrlrange
  learned_on  {"tasks", "env_steps", "seed", "method", "set"}: the run it comes from
  success     {task: final success, the mean of its last 3 evaluations} and, where the run
              has one, "closing": {task: its closing evaluation's success}
  date, release
An older synergy file (no format) still loads; its hand is unknown (None), and only its
action size is checked against an env.

Shipped files lie in synergies/shipped/ (NAME.npz and NAME.png, the hand along each synergy):
`shipped()` lists them; a NAME works wherever a synergy file's path does (`--decoder-from`,
`Synergies.load`).
"""

from __future__ import annotations

import dataclasses
import datetime
import pathlib
from typing import Any

import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.synergies import fitting

FORMAT = 2


class SynergyFileError(BadInput):
  """A synergy file or name that cannot be used: one line naming the file and why."""


def shipped() -> dict[str, str]:
  """{name: what it is} of the synergy files that ship with the package."""
  out = {}
  for path in sorted(fitting.SHIPPED.glob("*.npz")):
    meta, _ = fitting.read(path)
    learned = meta.get("learned_on", {})
    out[path.stem] = (f"{meta['hand']['name']}, b = {meta['n_synergies']}, {learned.get('method')} "
                      f"on {', '.join(learned.get('tasks', ()))}, seed {learned.get('seed')}")
  return out


def hand_of(hand_name: str) -> dict[str, Any]:
  """The hand part of a synergy file's meta: name, actuators in action order, ctrlranges."""
  from discosyn_jax.env import hands

  model, _ = hands._alone(hands.load(hand_name))
  return {"name": hands.label(hand_name),
          "actuators": [model.actuator(i).name for i in range(model.nu)],
          "ctrlrange": np.asarray(model.actuator_ctrlrange, float).round(6).tolist()}


def export(run_dir: str | pathlib.Path, path: str | pathlib.Path,
           date: str | None = None, method: str | None = None) -> pathlib.Path:
  """Write the synergy file of a finished run (its final decoder, or its record's
  decoder.npz) to `path`, with its hand, what it was learned on and how well; `method` its
  row's name where the run's experiment.json does not say it."""
  from discosyn_jax.run import folder

  run = folder.read(run_dir)
  config = run.config
  if config.kind.full_action:
    raise SynergyFileError(f"{run.path} is a full-action run: it has no synergies to export")
  meta, params = fitting.read(run.path)
  if not run.evaluations:
    raise SynergyFileError(f"{run.path} has no evaluation yet: export a run that has trained")
  end = run.at_end()  # the report's final: the mean of the last 3 evaluations
  success = {task: round(end[f"{task}/success"], 4) for task in config.tasks}
  extra = {}
  if run.closing:
    extra["closing"] = {task: run.closing[f"{task}/success"] for task in config.tasks}
  return fitting.save(
      path, params, meta, format=FORMAT, decoder_init=meta.get("decoder_init", "random"),
      hand=hand_of(config.hand),
      learned_on={"tasks": list(config.tasks), "env_steps": run.evaluations[-1]["env_steps"],
                  "seed": config.seed,
                  "method": run.labels.get("method", method),
                  "set": run.labels.get("set")},
      success={**success, **extra},
      date=date or datetime.date.today().isoformat(), release=_release())


def _release() -> str:
  """This package's version, as installed."""
  from importlib import metadata

  try:
    return metadata.version("discosyn-jax")
  except metadata.PackageNotFoundError:  # run from a checkout that was never installed
    return "unknown"


@dataclasses.dataclass(frozen=True)
class Synergies:
  """A synergy file as read: `decode(z)` the decoder's mean action, `matrix` its synergy
  basis (actions x b), `actuators` / `hand` what it drives, `learned_on` and `success` where
  it comes from. `Synergies.load(NAME_OR_PATH)` reads a shipped file, a file or a run."""
  meta: dict[str, Any]
  params: dict
  source: pathlib.Path

  @classmethod
  def load(cls, source: str | pathlib.Path) -> "Synergies":
    try:
      meta, params = fitting.read(source)  # a shipped name, a synergy file or a run folder
    except ValueError as err:
      raise SynergyFileError(str(err)) from None
    return cls(meta, params, fitting.resolve(source))

  @property
  def name(self) -> str:
    return self.source.stem if self.source.is_file() else self.source.name

  @property
  def b(self) -> int:
    return int(self.meta["n_synergies"])

  @property
  def action_size(self) -> int:
    return int(np.shape(self.params["log_std"])[-1])

  @property
  def hand(self) -> str | None:
    """The hand's name (None for a file of an older format, which did not say)."""
    hand = self.meta.get("hand")
    return hand["name"] if hand else None

  @property
  def actuators(self) -> tuple[str, ...] | None:
    hand = self.meta.get("hand")
    return tuple(hand["actuators"]) if hand else None

  @property
  def learned_on(self) -> dict[str, Any]:
    return dict(self.meta.get("learned_on", {}))

  @property
  def success(self) -> dict[str, Any]:
    return dict(self.meta.get("success", {}))

  @property
  def bounded(self) -> bool:
    """Whether the decoder reads tanh(z) (z bounded in training), so that what it reads is in
    [-1, 1]."""
    return bool(self.meta["squash_z"])

  @property
  def matrix(self) -> np.ndarray:
    """The synergy basis, actions x b: the linear decoder's W, an MLP's Jacobian at z = 0."""
    return fitting.basis(self.meta, self.params)

  def decode(self, z) -> np.ndarray:
    """The decoder's mean action for z as a policy head picks it (tanh(z) read where z is
    bounded), in [-1, 1] per actuator after the env's clip."""
    return fitting.decode(self.meta, self.params, np.asarray(z, np.float32))

  def check_hand(self, actuators, hand: str = "the env's hand") -> None:
    """Refuse, in one line naming both, an env whose actuators (in action order) are not
    the ones this file's decoder drives."""
    actuators = tuple(actuators)
    if self.actuators is None:
      if len(actuators) != self.action_size:
        raise SynergyFileError(f"{self.source} drives {self.action_size} actuators, {hand} has "
                               f"{len(actuators)}")
      return
    if actuators != self.actuators:
      raise SynergyFileError(f"{self.source} drives the {self.hand} hand ({len(self.actuators)} "
                             f"actuators), not {hand} ({len(actuators)} actuators"
                             + (", others or in another order)" if len(actuators) == len(self.actuators) else ")"))
