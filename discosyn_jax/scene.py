"""Scenes: `xml/scenes/<name>.xml` includes the arena, the hand and one task object."""

from __future__ import annotations

import mujoco

from discosyn_jax import assets


def load_spec(scene: str) -> mujoco.MjSpec:
  """The editable spec of a scene, for tasks that set parameters before compiling."""
  return mujoco.MjSpec.from_file(str(assets.xml_path(f"scenes/{scene}.xml")))
