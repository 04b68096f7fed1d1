"""tasks.make and the Brax Env interface."""

import subprocess
import sys
import zipfile

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from brax.envs.wrappers import training

import tasks


def test_unknown_task_lists_known_names():
  with pytest.raises(ValueError, match="unknown task 'valve9'.*valve0, valve1, valve2, valve3"):
    tasks.make("valve9")


def test_unknown_setting_is_named():
  with pytest.raises(ValueError, match="no setting frictoinloss"):
    tasks.make("valve3", frictoinloss=0.1)


def test_task_set_1_and_overrides():
  assert tasks.TASK_SETS["set1"] == ("valve0", "valve1", "valve2", "valve3")
  env = tasks.make("valve2", backend="native", frictionloss=0.3, damping=0.7)
  assert isinstance(env.mj_model, mujoco.MjModel)
  hinge = env.mj_model.joint("valve").dofadr[0]
  assert env.mj_model.dof_frictionloss[hinge] == pytest.approx(0.3)
  assert env.mj_model.dof_damping[hinge] == pytest.approx(0.7)
  assert (env.observation_size, env.action_size, env.backend) == (27, 20, "native")


def test_actions_map_to_joint_ranges_and_are_clipped():
  env = tasks.make("valve3", backend="native")
  lo, hi = env.mj_model.actuator_ctrlrange.T
  np.testing.assert_allclose(env.action_to_ctrl(-jnp.ones(20)), lo, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(jnp.ones(20)), hi, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(3 * jnp.ones(20)), hi, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(jnp.zeros(20)), (lo + hi) / 2, atol=1e-6)


def test_brax_training_wrappers_run_it():
  env = training.wrap(tasks.make("valve1", backend="native"), episode_length=5)
  state = jax.jit(env.reset)(jax.random.split(jax.random.PRNGKey(0), 3))
  step = jax.jit(env.step)
  dones = []
  for _ in range(6):
    state = step(state, jnp.zeros((3, 20)))
    dones.append(np.asarray(state.done))
    assert np.isfinite(np.asarray(state.obs)).all()
  # the episode wrapper ends every episode at step 5, the auto-reset starts the next
  assert [d.all() for d in dones] == [False, False, False, False, True, False]
  assert np.asarray(state.info["steps"]).tolist() == [1, 1, 1]
  assert "reward/turn" in state.metrics


def test_a_wheel_carries_the_xml_and_works_outside_the_checkout(tmp_path):
  """What a non-editable `pip install .` gets: tasks and the MJCF files from the wheel."""
  root = __import__("pathlib").Path(__file__).resolve().parents[1]
  subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                  "-w", str(tmp_path / "wheel"), str(root)], check=True, capture_output=True)
  (wheel,) = (tmp_path / "wheel").glob("*.whl")
  with zipfile.ZipFile(wheel) as zf:
    names = set(zf.namelist())
    assert {"discosyn_jax/xml/hand.xml", "discosyn_jax/xml/scenes/valve3.xml",
            "discosyn_jax/xml/objects/valve0.xml", "tasks/valve.py"} <= names
    zf.extractall(tmp_path / "site")
  code = ("import tasks, discosyn_jax.assets as a; env = tasks.make('valve3', backend='native');"
          "print('RESULT', tasks.__file__, a.xml_dir(), env.observation_size)")
  out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       env={"PYTHONPATH": str(tmp_path / "site"), "PATH": "/usr/bin:/bin"})
  assert out.returncode == 0, out.stderr
  (line,) = [l for l in out.stdout.splitlines() if l.startswith("RESULT")]  # mjx prints too
  lines = line.split()[1:]
  assert lines[0].startswith(str(tmp_path / "site"))
  assert lines[1] == str(tmp_path / "site" / "discosyn_jax" / "xml")
  assert lines[2] == "27"
