"""Hand-written motions: proof that a deliberate policy can do the tasks, per shipped hand.

Our hand (shadow20), strokes of 1.33 s: fingers straight and the wrist swung clockwise (WRJ1
low), the four fingers dipped into the valve's plane, then the wrist swung counter-clockwise
(WRJ1 up), which drags whatever the fingers hold or touch counter-clockwise about the
valve's axis. leap16 has no wrist: its fingers dip and sweep sideways (leap_sweep).

Which motion a task gets is the task's own declaration (Task.motion: a Motion below).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.env import hands

# our hand's actuators in action order, by joint name ("A_WRJ1" -> "WRJ1")
_A = {name.removeprefix("A_"): i for i, name in enumerate(hands.actuators("shadow20"))}
_FLEX = ("FFJ2", "MFJ2", "RFJ2", "LFJ2")
_CURL = ("FFJ1", "MFJ1", "RFJ1", "LFJ1")


def grasp_and_sweep(steps: int, dt: float, stroke_s: float = 1.33, dip: float = 0.0,
                    curl: float = 0.3, direction: float = 1.0) -> np.ndarray:
  """Our hand, (steps, 20) actions in [-1, 1]; `dip` and `curl` are the J2 and J1 actions when down;
  `direction` -1 mirrors the wrist's sweep (clockwise seen from above)."""
  actions = np.full((steps, len(_A)), -1.0)  # straight fingers, joints at a limit
  for name in ("FFJ3", "MFJ3", "RFJ3", "LFJ3", "LFJ4", "THJ2", "THJ1", "WRJ0"):
    actions[:, _A[name]] = 0.0  # mid-range
  phase = (np.arange(steps) * dt) % stroke_s / stroke_s
  down = (phase >= 0.25) & (phase < 0.95)
  sweep = np.clip((phase - 0.4) / 0.5, 0.0, 1.0)  # wrist ramps CCW during the dipped part
  actions[:, _A["WRJ1"]] = direction * np.where(down, -1.0 + 2.0 * sweep, -1.0)
  for name in _FLEX:
    actions[:, _A[name]] = np.where(down, dip, -1.0)
  for name in _CURL:
    actions[:, _A[name]] = np.where(down, curl, -1.0)
  return actions


def hook_and_lift(steps: int, dt: float, curl_at: float = 1.0, lift_at: float = 2.0) -> np.ndarray:
  """weight_pull: fingers straight, then bent down and in around the rope's handle bar
  (J2 and J1 actions 0.6 and -0.5, from `curl_at` s), then the wrist pitched up (from
  `lift_at` s), which lifts the hooked bar."""
  t = np.arange(steps) * dt
  actions = np.zeros((steps, len(_A)))
  for name in _FLEX:
    actions[:, _A[name]] = np.where(t < curl_at, -1.0, 0.6)
  for name in _CURL:
    actions[:, _A[name]] = np.where(t < curl_at, -1.0, -0.5)
  actions[:, _A["WRJ0"]] = np.where(t < lift_at, 0.0, -1.0)  # WRJ0 low: fingertips up
  return actions


def finger_roll(steps: int, dt: float, stroke_s: float = 0.6) -> np.ndarray:
  """screw: the four fingers press on the top of the handle lying across them and curl in
  towards the palm (J2 actions -0.3 -> 0.3, J1 -1 -> 1 over 60 % of each stroke), then
  straighten and reach out again: each stroke rolls the handle about +x, screwing it in."""
  phase = (np.arange(steps) * dt) % stroke_s / stroke_s
  down = phase < 0.6
  actions = np.zeros((steps, len(_A)))
  for name in _FLEX:
    actions[:, _A[name]] = np.where(down, -0.3 + phase, -1.0)
  for name in _CURL:
    actions[:, _A[name]] = np.where(down, -1.0 + phase / 0.3, -1.0)
  return actions


def leap_sweep(steps: int, dt: float, stroke_s: float = 1.33, dip: float = 0.3,
               direction: float = 1.0) -> np.ndarray:
  """leap16, (steps, 16): strokes like grasp_and_sweep's without a wrist: the three fingers
  turned to one side (rot), bent down into the valve's plane (MCP action `dip`, PIP and DIP
  straight), swept to the other side, then lifted and turned back. Sweeping to +x drags
  what they touch counter-clockwise seen from above; `direction` -1 mirrors it."""
  index = {name: i for i, name in enumerate(hands.actuators("leap16"))}
  actions = np.full((steps, len(index)), -1.0)  # joints at their lower limits: fingers straight
  phase = (np.arange(steps) * dt) % stroke_s / stroke_s
  down = (phase >= 0.25) & (phase < 0.95)
  sweep = np.clip((phase - 0.4) / 0.5, 0.0, 1.0)
  for finger in ("if", "mf", "rf"):
    actions[:, index[f"{finger}_rot"]] = direction * np.where(down, -0.6 + 1.2 * sweep, -0.6)
    actions[:, index[f"{finger}_mcp"]] = np.where(down, dip, -0.6)
    actions[:, index[f"{finger}_pip"]] = -0.6
    actions[:, index[f"{finger}_dip"]] = -0.6
  return actions


@dataclasses.dataclass(frozen=True)
class Motion:
  """The deliberate motion a task declares (Task.motion), on each shipped hand: on ours
  `script(steps, dt, **options)`, one of the scripts above; on leap16, which has no wrist,
  leap_sweep in `leap_direction`, whatever the task."""
  script: Callable[..., np.ndarray] = grasp_and_sweep
  options: Mapping[str, float] = dataclasses.field(default_factory=dict)
  leap_direction: float = 1.0

  def actions(self, steps: int, dt: float, hand: str = hands.DEFAULT) -> np.ndarray:
    """(steps, actuators) actions in [-1, 1] on shipped `hand`; BadInput for a hand without
    scripts."""
    if hand == "leap16":
      return leap_sweep(steps, dt, direction=self.leap_direction)
    if hand != "shadow20":
      raise BadInput(f"no scripted motions for hand {hand}: only for {', '.join(hands.SHIPPED)}")
    return self.script(steps, dt, **self.options)
