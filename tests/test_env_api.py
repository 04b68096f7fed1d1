"""tasks.make and the Brax Env interface."""

import os
import shutil
import subprocess
import sys
import zipfile

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from brax.envs.wrappers import training

from discosyn_jax import tasks
from tests import helpers


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
  env = helpers.env("valve3")
  lo, hi = env.mj_model.actuator_ctrlrange.T
  np.testing.assert_allclose(env.action_to_ctrl(-jnp.ones(20)), lo, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(jnp.ones(20)), hi, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(3 * jnp.ones(20)), hi, atol=1e-6)
  np.testing.assert_allclose(env.action_to_ctrl(jnp.zeros(20)), (lo + hi) / 2, atol=1e-6)


def test_brax_training_wrappers_run_it():
  env = training.wrap(helpers.env("valve1"), episode_length=5)
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


def test_brax_own_ppo_trains_and_evaluates_on_a_task():
  """Brax's trainer wraps the env in its own wrappers (EvalWrapper adds a "reward" metric):
  their keys must survive the env's step. (What Brax calls of JAX that JAX removed is given
  back as Brax is imported, quiet_mjx.py: tests/test_brax_user.py runs it from a script.)"""
  from brax.training.agents.ppo import train as brax_ppo

  evaluations = []
  _, params, metrics = brax_ppo.train(
      helpers.env("valve1"), num_timesteps=40, episode_length=10, num_envs=4,
      batch_size=4, unroll_length=5, num_minibatches=2, num_updates_per_batch=1, num_evals=2,
      num_eval_envs=2, seed=0, progress_fn=lambda step, m: evaluations.append(step))
  assert evaluations == [0, 40]  # one evaluation before training, one after its step
  assert np.isfinite(metrics["eval/episode_reward"])
  assert 0.0 <= metrics["eval/episode_success"] <= 10.0  # summed over the 10-step episode
  assert "eval/episode_reward/turn" in metrics
  assert all(np.isfinite(x).all() for x in jax.tree.leaves(params))


def test_a_wheel_carries_the_xml_and_works_outside_the_checkout(tmp_path):
  """What a non-editable `pip install .` gets: tasks and the MJCF files from the wheel."""
  root = __import__("pathlib").Path(__file__).resolve().parents[1]
  # built from a copy: setuptools writes build/ and *.egg-info next to the sources
  source = tmp_path / "source"
  shutil.copytree(root, source, ignore=shutil.ignore_patterns(
      ".git", ".venv*", "runs", "build", "*.egg-info", "__pycache__", ".pytest_cache", "docs"))
  subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                  "-w", str(tmp_path / "wheel"), str(source)], check=True, capture_output=True)
  (wheel,) = (tmp_path / "wheel").glob("*.whl")
  with zipfile.ZipFile(wheel) as zf:
    names = set(zf.namelist())
    assert {"discosyn_jax/xml/hands/shadow20.xml", "discosyn_jax/xml/hands/leap16.xml",
            "discosyn_jax/xml/objects/valve0.xml", "discosyn_jax/tasks/valve.py",
            "discosyn_jax/experiments/presets.py",
            "discosyn_jax/synergies/shipped/shadow20-set1.npz"} <= names
    # two top-level names, both the project's own: none a user's tasks.py could shadow
    assert {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")} == {
        "discosyn", "discosyn_jax"}
    zf.extractall(tmp_path / "site")
  code = ("from discosyn_jax import tasks; import discosyn_jax.env.assets as a; env = tasks.make('valve3', backend='native');"
          "import discosyn_jax as ds; s = ds.Synergies.load('leap16-set1');"
          "print('RESULT', tasks.__file__, a.xml_dir(), env.observation_size, s.b, s.hand, s.source)")
  out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       env={"PYTHONPATH": str(tmp_path / "site"), "PATH": "/usr/bin:/bin",
                            "HOME": os.environ["HOME"], "DISCOSYN_JAX_CACHE": "off"})
  assert out.returncode == 0, out.stderr
  (line,) = [l for l in out.stdout.splitlines() if l.startswith("RESULT")]  # mjx prints too
  lines = line.split()[1:]
  assert lines[0].startswith(str(tmp_path / "site"))
  assert lines[1] == str(tmp_path / "site" / "discosyn_jax" / "xml")
  assert lines[2] == "27"
  # a shipped synergy file, by name, from the installed package
  assert lines[3:5] == ["3", "leap16"]
  assert lines[5] == str(tmp_path / "site" / "discosyn_jax" / "synergies" / "shipped" / "leap16-set1.npz")
