"""A hand-written turning motion: proof that a deliberate policy can turn the valves.

Strokes of 1.33 s: fingers straight and the wrist swung clockwise (WRJ1 low), the four
fingers dipped into the valve's plane, then the wrist swung counter-clockwise (WRJ1 up),
which drags whatever the fingers hold or touch counter-clockwise about the valve's axis.
"""

from __future__ import annotations

import numpy as np

from discosyn_jax import hand

_A = {name: i for i, name in enumerate(hand.ACTUATED)}
_FLEX = ("FFJ2", "MFJ2", "RFJ2", "LFJ2")
_CURL = ("FFJ1", "MFJ1", "RFJ1", "LFJ1")


def grasp_and_sweep(steps: int, dt: float, stroke_s: float = 1.33, dip: float = 0.0,
                    curl: float = 0.3) -> np.ndarray:
  """(steps, 20) actions in [-1, 1]; `dip` and `curl` are the J2 and J1 actions when down."""
  actions = np.full((steps, len(hand.ACTUATED)), -1.0)  # straight fingers, joints at a limit
  for name in ("FFJ3", "MFJ3", "RFJ3", "LFJ3", "LFJ4", "THJ2", "THJ1", "WRJ0"):
    actions[:, _A[name]] = 0.0  # mid-range
  phase = (np.arange(steps) * dt) % stroke_s / stroke_s
  down = (phase >= 0.25) & (phase < 0.95)
  sweep = np.clip((phase - 0.4) / 0.5, 0.0, 1.0)  # wrist ramps CCW during the dipped part
  actions[:, _A["WRJ1"]] = np.where(down, -1.0 + 2.0 * sweep, -1.0)
  for name in _FLEX:
    actions[:, _A[name]] = np.where(down, dip, -1.0)
  for name in _CURL:
    actions[:, _A[name]] = np.where(down, curl, -1.0)
  return actions
