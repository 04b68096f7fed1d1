"""Offscreen pictures of scenes with MuJoCo's renderer.

Headless machines need an OpenGL library: set MUJOCO_GL=egl (Debian/Ubuntu packages
libegl1 and libgl1-mesa-dri, software-rendered without a GPU) or MUJOCO_GL=osmesa
(package libosmesa6). `discosyn render-scenes` picks egl when nothing is set.
"""

from __future__ import annotations

import os

import mujoco
import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")


def frames(model: mujoco.MjModel, data: mujoco.MjData, cameras=("front", "oblique"),
           height: int = 360, width: int = 480) -> np.ndarray:
  """The views of `cameras`, side by side, as one (height, width * n, 3) uint8 image."""
  with mujoco.Renderer(model, height, width) as renderer:
    views = []
    for camera in cameras:
      renderer.update_scene(data, camera=camera)
      views.append(renderer.render())
  return np.concatenate(views, axis=1)
