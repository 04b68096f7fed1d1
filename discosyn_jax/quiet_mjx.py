"""MuJoCo's MJX imported without the "Failed to import warp" lines it prints on stdout
wherever the optional Warp packages are absent (the CPU path never needs them). Importing
this module does it: every module of the library that imports brax or MJX imports this one
first."""

from __future__ import annotations

import contextlib
import io
import sys

_NOISE = ("Failed to import warp", "Failed to import mujoco_warp")


def import_mjx() -> None:
  if "mujoco.mjx" in sys.modules:
    return
  captured = io.StringIO()
  with contextlib.redirect_stdout(captured):
    import mujoco.mjx  # noqa: F401
  for line in captured.getvalue().splitlines():
    if not line.startswith(_NOISE):
      print(line, file=sys.stdout)


import_mjx()
