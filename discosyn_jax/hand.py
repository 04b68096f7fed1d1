"""Names of the hand's joints and actuators, in model order."""

from __future__ import annotations

import mujoco
import numpy as np

JOINTS = (
    "WRJ1", "WRJ0",
    "FFJ3", "FFJ2", "FFJ1", "FFJ0",
    "MFJ3", "MFJ2", "MFJ1", "MFJ0",
    "RFJ3", "RFJ2", "RFJ1", "RFJ0",
    "LFJ4", "LFJ3", "LFJ2", "LFJ1", "LFJ0",
    "THJ4", "THJ3", "THJ2", "THJ1", "THJ0",
)  # fmt: skip
# the distal J0 of FF/MF/RF/LF follows J1 through an equality: not actuated
ACTUATED = tuple(j for j in JOINTS if not (j.endswith("J0") and not j.startswith(("TH", "WR"))))


def qpos_indices(model: mujoco.MjModel) -> np.ndarray:
  """qpos addresses of the 24 hand joints, in JOINTS order."""
  return np.array([model.jnt_qposadr[model.joint(j).id] for j in JOINTS])


def qvel_indices(model: mujoco.MjModel) -> np.ndarray:
  return np.array([model.jnt_dofadr[model.joint(j).id] for j in JOINTS])
