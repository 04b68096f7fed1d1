"""Our hand's model (xml/hands/shadow20.xml) against the numbers of TASKS.md (a spec written
down here, not read from the model). Any hand, and leap16: tests/test_hands.py."""

import mujoco
import numpy as np
import pytest

from discosyn_jax.env import assets

JOINTS = (
    "WRJ1", "WRJ0",
    "FFJ3", "FFJ2", "FFJ1", "FFJ0",
    "MFJ3", "MFJ2", "MFJ1", "MFJ0",
    "RFJ3", "RFJ2", "RFJ1", "RFJ0",
    "LFJ4", "LFJ3", "LFJ2", "LFJ1", "LFJ0",
    "THJ4", "THJ3", "THJ2", "THJ1", "THJ0",
)  # fmt: skip
# TASKS.md: fingertips at the zero pose, in the palm frame
TIPS = {
    "fftip": (0.033, 0, 0.191), "mftip": (0.011, 0, 0.195), "rftip": (-0.011, 0, 0.191),
    "lftip": (-0.034, 0, 0.184), "thtip": (0.103, -0.009, 0.098),
}
# TASKS.md: joint ranges
RANGES = {
    "WRJ1": (-0.489, 0.14), "WRJ0": (-0.698, 0.489),
    **{f"{f}J3": (-0.349, 0.349) for f in ("FF", "MF", "RF", "LF")},
    **{f"{f}J{k}": (0, 1.571) for f in ("FF", "MF", "RF", "LF") for k in (2, 1, 0)},
    "LFJ4": (0, 0.785),
    "THJ4": (-1.047, 1.047), "THJ3": (0, 1.222), "THJ2": (-0.209, 0.209),
    "THJ1": (-0.524, 0.524), "THJ0": (-1.571, 0),
}
# TASKS.md: the 20 actuators in order, with force limits
ACTUATORS = [
    ("WRJ1", 4.785), ("WRJ0", 2.175), ("FFJ3", 0.9), ("FFJ2", 0.9), ("FFJ1", 0.7245),
    ("MFJ3", 0.9), ("MFJ2", 0.9), ("MFJ1", 0.7245), ("RFJ3", 0.9), ("RFJ2", 0.9),
    ("RFJ1", 0.7245), ("LFJ4", 0.9), ("LFJ3", 0.9), ("LFJ2", 0.9), ("LFJ1", 0.7245),
    ("THJ4", 2.3722), ("THJ3", 1.45), ("THJ2", 0.99), ("THJ1", 0.99), ("THJ0", 0.81),
]


@pytest.fixture(scope="module")
def model():
  return mujoco.MjModel.from_xml_path(str(assets.xml_path("hands/shadow20.xml")))


def test_sizes(model):
  assert (model.njnt, model.nq, model.nu) == (24, 24, 20)
  assert [model.joint(i).name for i in range(model.njnt)] == list(JOINTS)


def test_fingertips_at_zero_pose(model):
  data = mujoco.MjData(model)
  mujoco.mj_forward(model, data)
  palm = data.body("palm")
  rot = palm.xmat.reshape(3, 3)
  for site, expected in TIPS.items():
    local = rot.T @ (data.site(site).xpos - palm.xpos)
    np.testing.assert_allclose(local, expected, atol=0.003, err_msg=site)


def test_joint_ranges(model):
  assert set(RANGES) == set(JOINTS)
  for name, rng in RANGES.items():
    np.testing.assert_allclose(model.joint(name).range, rng, atol=1e-6, err_msg=name)


def test_actuators_order_targets_and_limits(model):
  assert [model.actuator(i).name for i in range(model.nu)] == [f"A_{j}" for j, _ in ACTUATORS]
  for i, (joint, force) in enumerate(ACTUATORS):
    assert model.actuator_trnid[i, 0] == model.joint(joint).id
    np.testing.assert_allclose(model.actuator_forcerange[i], (-force, force))
    np.testing.assert_allclose(model.actuator_ctrlrange[i], RANGES[joint])
    assert model.actuator_gainprm[i, 0] == (5 if joint.startswith("WR") else 1)


def test_primitives_only_and_no_self_collision(model):
  prims = {int(g) for g in (mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_SPHERE)}
  assert {int(t) for t in model.geom_type} <= prims
  colliding = [i for i in range(model.ngeom) if model.geom_contype[i]]
  assert all(model.geom_conaffinity[i] == 0 for i in colliding)  # never hand against hand


def test_distal_joints_follow_j1(model):
  data = mujoco.MjData(model)
  data.ctrl[:] = model.actuator_ctrlrange.mean(axis=1)
  for _ in range(500):
    mujoco.mj_step(model, data)
  for finger in ("FF", "MF", "RF", "LF"):
    j1, j0 = data.joint(f"{finger}J1").qpos[0], data.joint(f"{finger}J0").qpos[0]
    assert j1 > 0.5  # it did flex towards mid-range
    assert abs(j0 - j1) < 0.02, finger
