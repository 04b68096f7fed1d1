"""Offscreen pictures of scenes with MuJoCo's renderer.

Headless machines need an OpenGL library: set MUJOCO_GL=egl (Debian/Ubuntu packages
libegl1, libegl-mesa0 and libgl1-mesa-dri, software-rendered without a GPU) or MUJOCO_GL=osmesa
(package libosmesa6). On Linux without a display, importing discosyn_jax sets egl when
nothing is set (MuJoCo reads the variable when it is imported).
"""

from __future__ import annotations

import pathlib
from typing import Iterable, Iterator

import mujoco
import numpy as np

from discosyn_jax.checks import BadInput


def frames(model: mujoco.MjModel, data: mujoco.MjData, cameras=("front", "oblique"),
           height: int = 360, width: int = 480) -> np.ndarray:
  """The views of `cameras`, side by side, as one (height, width * n, 3) uint8 image."""
  return next(many_frames(model, [data], cameras, height, width))


def many_frames(model: mujoco.MjModel, datas: Iterable[mujoco.MjData], cameras=("front", "oblique"),
                height: int = 360, width: int = 480) -> Iterator[np.ndarray]:
  """`frames` of each state in `datas`, through one renderer (one GL context for a whole video)."""
  with mujoco.Renderer(model, height, width) as renderer:
    for data in datas:
      views = []
      for camera in cameras:
        renderer.update_scene(data, camera=camera)
        views.append(renderer.render())
      yield np.concatenate(views, axis=1)


def check_size(model: mujoco.MjModel, height: int, width: int) -> None:
  """Refuse a picture size the model's offscreen buffer cannot hold (its <visual><global
  offheight offwidth>), before anything is rolled out or drawn."""
  for name, value, most in (("height", height, model.vis.global_.offheight),
                            ("width", width, model.vis.global_.offwidth)):
    if not 1 <= value <= most:
      raise BadInput(f"--{name} must be between 1 and {most} pixels, not {value}")


def check_new(paths, force: bool) -> None:
  """Refuse to overwrite pictures or videos already there, unless `force`."""
  if force:
    return
  for path in paths:
    if pathlib.Path(path).exists():
      raise BadInput(f"{path} already exists; pass --force to replace it")
