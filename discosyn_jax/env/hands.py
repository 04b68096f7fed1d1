"""Hands: an MJCF file and the site that marks its palm; where a scene puts any hand.

A scene attaches the hand to the arena under the prefix "hand/" ("hand/WRJ1", ...), so a task
finds the hand's joints by that prefix, whatever the hand. Every actuator of the hand is one
action, in the file's order, mapped from [-1, 1] onto its ctrlrange (hand_env.py).

The palm site fixes where the hand goes. Its frame: origin on the palm's surface, in its
middle; z along the fingers; +y out of the back of the hand (the palmar normal is -y). The
scene moves the whole hand so that this site lands where ours has it, above the objects,
palm down (PALM_SITE), or turned half a turn about the forearm's axis (PALM_UP); so the
objects of every task sit where they do for our hand. Shipped hands: SHIPPED (xml/hands/).
"""

from __future__ import annotations

import dataclasses
import functools
import pathlib

import mujoco
import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.env import assets

PREFIX = "hand/"
DEFAULT = "shadow20"
SHIPPED = {
    "shadow20": "our 20-actuator Shadow-style hand with a 2-joint wrist (the paper's)",
    "leap16": "a LEAP-like four-finger hand, 16 actuators, no wrist, built from published numbers",
}
PALM_SITE_NAME = "palm_center"
# Where the palm site of every hand lies in the world, palm down: the world pose of our hand's
# site, its z (the fingers) along world +y, its back (+y) up.
PALM_SITE = (np.array([0.0, -0.05, 0.2139]),
             np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]))
# Mounts: rigid moves of the palm-down hand, (translation, rotation matrix) in the world.
PALM_DOWN = (np.zeros(3), np.eye(3))
# half a turn about the forearm's axis (world y through x = 0, z = 0.225): the palm faces up
PALM_UP = (np.array([0.0, 0.0, 0.45]), np.diag([-1.0, 1.0, -1.0]))


@dataclasses.dataclass(frozen=True)
class Hand:
  """`name`: a shipped hand's name, or the MJCF file's absolute path (with ":SITE" where the
  palm site is not "palm_center"), as a run's config keeps it."""
  name: str
  mjcf: pathlib.Path
  palm_site: str = PALM_SITE_NAME


def load(spec: str | Hand) -> Hand:
  """The hand of `spec`: a shipped hand's name, or "path/to/hand.xml" ("...xml:SITE" names
  the palm site). BadInput in one line for a wrong spec or a file that is no hand."""
  if isinstance(spec, Hand):
    return spec
  if spec in SHIPPED:
    hand = Hand(spec, assets.xml_path(f"hands/{spec}.xml"))
  else:
    where, _, site = spec.partition(".xml")
    if ".xml" not in spec or not where or (site and not site.startswith(":")):
      raise BadInput(f"a hand is one of {', '.join(SHIPPED)} or an MJCF file "
                     f"(path/to/hand.xml, or path/to/hand.xml:PALM_SITE), not {spec!r}")
    path = pathlib.Path(where + ".xml").expanduser().resolve()
    site = site.removeprefix(":") or PALM_SITE_NAME
    if not path.is_file():
      raise BadInput(f"no hand MJCF file {where}.xml")
    name = str(path) if site == PALM_SITE_NAME else f"{path}:{site}"
    hand = Hand(name, path, site)
  check(hand)
  return hand


def read(hand: Hand) -> mujoco.MjSpec:
  """The hand's own MJCF as an editable spec (its meshes found beside its file)."""
  try:
    return mujoco.MjSpec.from_file(str(hand.mjcf))
  except ValueError as err:
    raise BadInput(f"hand {hand.mjcf}: {' '.join(str(err).split())}") from None


@functools.cache
def _alone(hand: Hand) -> tuple[mujoco.MjModel, mujoco.MjData]:
  """The hand compiled alone, at its reference pose (read, never changed)."""
  spec = read(hand)
  try:
    model = spec.compile()
  except ValueError as err:
    raise BadInput(f"hand {hand.mjcf}: {' '.join(str(err).split())}") from None
  data = mujoco.MjData(model)
  mujoco.mj_kinematics(model, data)
  return model, data


def check(hand: Hand) -> None:
  """A BadInput naming the first thing that makes the file no hand for the tasks."""
  model, _ = _alone(hand)
  where = f"hand {hand.name}"
  if model.nu == 0:
    raise BadInput(f"{where}: the MJCF has no actuators (each actuator is one action)")
  unbounded = [model.actuator(i).name or str(i) for i in range(model.nu)
               if not model.actuator_ctrllimited[i]]
  if unbounded:
    raise BadInput(f"{where}: actuator {unbounded[0]} has no ctrlrange (actions map onto it)")
  wrong = [model.joint(j).name or str(j) for j in range(model.njnt)
           if model.jnt_type[j] not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))]
  if wrong:
    raise BadInput(f"{where}: joint {wrong[0]} is free or a ball; a hand has a fixed root "
                   "and hinge or slide joints")
  if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, hand.palm_site) < 0:
    raise BadInput(f"{where}: no site named {hand.palm_site!r} marks the palm (its frame: "
                   "z along the fingers, +y out of the back of the hand; docs/YOUR_HAND.md)")


def _pose(pos: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
  return np.asarray(pos, float), np.asarray(rot, float).reshape(3, 3)


def placement(hand: Hand, mount=PALM_DOWN) -> tuple[list[float], list[float]]:
  """(pos, quat) of the frame that carries the hand's file into the scene: its palm site
  at PALM_SITE moved by `mount`. Rounded to 1e-9, so that our hand, whose file already has
  its palm there, is carried by the identity and compiles to the very same model."""
  _, data = _alone(hand)
  site = data.site(hand.palm_site)
  s0_pos, s0_rot = _pose(site.xpos, site.xmat)
  target_pos, target_rot = PALM_SITE
  mount_pos, mount_rot = mount
  rot = mount_rot @ target_rot @ s0_rot.T
  pos = mount_rot @ (target_pos - target_rot @ s0_rot.T @ s0_pos) + mount_pos
  quat = np.zeros(4)
  mujoco.mju_mat2Quat(quat, rot.flatten())
  clean = lambda v: [float(x) + 0.0 for x in np.round(v, 9)]  # + 0.0: no -0.0
  return clean(pos), clean(quat)


def label(name: str) -> str:
  """A hand as folders and reports name it: a shipped hand's name, a file's stem."""
  return pathlib.Path(name.partition(".xml")[0]).name if ".xml" in name else name


def joint_ids(model: mujoco.MjModel) -> np.ndarray:
  """Ids of the hand's joints in a scene's model, in model order."""
  return np.array([j for j in range(model.njnt) if model.joint(j).name.startswith(PREFIX)], int)


def actuator_names(model: mujoco.MjModel) -> list[str]:
  """The hand's actuators in a scene's model, by their names in the hand's file."""
  return [model.actuator(i).name.removeprefix(PREFIX) for i in range(model.nu)]


def qpos_indices(model: mujoco.MjModel) -> np.ndarray:
  """qpos addresses of the hand's joints in a scene's model, in model order."""
  return model.jnt_qposadr[joint_ids(model)]


def qvel_indices(model: mujoco.MjModel) -> np.ndarray:
  return model.jnt_dofadr[joint_ids(model)]


def actuators(hand: str | Hand) -> list[str]:
  """The names of `hand`'s actuators in its file, in action order."""
  model, _ = _alone(load(hand))
  return [model.actuator(i).name for i in range(model.nu)]
