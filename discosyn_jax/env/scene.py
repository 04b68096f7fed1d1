"""Scenes: the arena (xml/arena.xml), a hand (hands.py) and one task object, composed here.

The object is `xml/objects/<name>.xml` for our tasks, or a task's own object MJCF file (a
path, docs/YOUR_TASK.md); the scene named "hand" has none. The object keeps its names (a
task looks up "valve"); the hand's get the prefix hands.PREFIX. Each part's files (meshes)
are found beside its own MJCF file.
"""

from __future__ import annotations

import pathlib
import warnings

import mujoco

from discosyn_jax.checks import BadInput
from discosyn_jax.env import assets, hands

# An object keeps its names: MuJoCo then warns, at the attach and at every compile, that the
# spec may not save back to XML, which is never done here.
warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")


def _attach_unprefixed(spec: mujoco.MjSpec, child: mujoco.MjSpec) -> None:
  """Attach `child` to the world keeping its names. MuJoCo's default warning handler would
  also write that warning to MUJOCO_LOG.TXT in the working folder: held off for the call."""
  handler = mujoco.get_mju_user_warning()
  mujoco.set_mju_user_warning(lambda message: None)
  try:
    spec.attach(child, frame=spec.worldbody.add_frame(), prefix="")
  finally:
    mujoco.set_mju_user_warning(handler)


def _object(scene: str | pathlib.Path) -> mujoco.MjSpec:
  if isinstance(scene, pathlib.Path):
    if not scene.is_file():
      raise BadInput(f"no object MJCF file {scene}")
    try:
      return mujoco.MjSpec.from_file(str(scene.resolve()))
    except ValueError as err:
      raise BadInput(f"{scene}: {str(err).strip()}") from None
  return mujoco.MjSpec.from_file(str(assets.xml_path(f"objects/{scene}.xml")))


def load_spec(scene: str | pathlib.Path, hand: str | hands.Hand = hands.DEFAULT,
              mount=hands.PALM_DOWN) -> mujoco.MjSpec:
  """The editable spec of a scene, for tasks that set parameters before compiling: the arena,
  `hand` placed by `mount` (hands.PALM_DOWN or hands.PALM_UP) and the object of `scene` (an
  object of xml/objects/ by name, a path to an object MJCF file, or "hand": none)."""
  hand = hands.load(hand)
  spec = mujoco.MjSpec.from_file(str(assets.xml_path("arena.xml")))
  spec.modelname = scene.stem if isinstance(scene, pathlib.Path) else scene
  pos, quat = hands.placement(hand, mount)
  spec.attach(_touching_objects_only(hands.read(hand)),
              frame=spec.worldbody.add_frame(pos=pos, quat=quat), prefix=hands.PREFIX)
  if scene != "hand":
    _attach_unprefixed(spec, _object(scene))
  return spec


def _touching_objects_only(hand: mujoco.MjSpec) -> mujoco.MjSpec:
  """The hand's colliding geoms get contype 1 / conaffinity 0, as ours have: the hand touches
  the objects (conaffinity 1), never itself or the floor. A hand file of one's own may collide
  otherwise; self-contact would cost MJX dearly and no task needs it."""
  for geom in hand.geoms:
    if geom.contype or geom.conaffinity:
      geom.contype, geom.conaffinity = 1, 0
  return hand
