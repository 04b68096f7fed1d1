"""Scenes: `xml/scenes/<name>.xml` includes the arena, the hand and one task object; a task
of one's own names its object's MJCF file instead (docs/YOUR_TASK.md)."""

from __future__ import annotations

import pathlib

import mujoco

from discosyn_jax import assets

# Where the forearm (the hand's fixed root) is mounted: position and xyaxes in the world.
# Palm down (hand.xml's own pose): the palm-frame point (0.011, 0, 0.11), the middle of the
# knuckle line, lies at world (0, 0, 0.225) and the palm faces -z.
# Palm up, for objects that rest on the palm: the same knuckle point, the palm facing +z
# (palm x -> world +x, palm y -> world -z); the palm's surface is at world z 0.2361.
PALM_UP = ((-0.011, -0.4, 0.225), (1, 0, 0, 0, 0, -1))


def load_spec(scene: str | pathlib.Path) -> mujoco.MjSpec:
  """The editable spec of a scene, for tasks that set parameters before compiling: a scene
  of xml/scenes/ by name, or an object's MJCF file (a path) put in the arena with the hand."""
  if isinstance(scene, pathlib.Path):
    if not scene.is_file():
      raise ValueError(f"no object MJCF file {scene}")
    parts = [assets.xml_path("arena.xml"), assets.xml_path("hand.xml"), scene.resolve()]
    includes = "".join(f'<include file="{path}"/>' for path in parts)
    try:
      return mujoco.MjSpec.from_string(f'<mujoco model="{scene.stem}">{includes}</mujoco>')
    except ValueError as err:
      raise ValueError(f"{scene}: {err}") from None
  return mujoco.MjSpec.from_file(str(assets.xml_path(f"scenes/{scene}.xml")))


def mount_hand(spec: mujoco.MjSpec, mount: tuple) -> None:
  """Move the hand's forearm to `mount` = (pos, xyaxes), e.g. PALM_UP."""
  pos, xyaxes = mount
  forearm = spec.body("forearm")
  forearm.pos = list(pos)
  forearm.alt.type = mujoco.mjtOrientation.mjORIENTATION_XYAXES
  forearm.alt.xyaxes = list(xyaxes)
