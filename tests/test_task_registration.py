"""One registration path: a task of the package's kind, declared here with its own fast physics
and scripted motion, is registered through `register` as ours are, trains through the
command line, and the registry builds it with its own declarations; bad registrations are
refused in one line."""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

import discosyn_jax.tasks.registry as registry
from discosyn import cli
from discosyn_jax.env import scripted
from discosyn_jax.env.task import Task, TaskConfig
from discosyn_jax.tasks import common, planted
from tests import toy_env

TINY = ["--num-envs", "2", "--unroll-length", "4", "--minibatches", "2", "--epochs", "1",
        "--steps", "1", "--eval-envs", "2", "--eval-every", "0", "--checkpoint-every", "0",
        "--backend", "native", "--no-progress"]


@dataclasses.dataclass(frozen=True)
class HoldConfig(TaskConfig):
  episode_length: int = 5


class Hold(Task):
  """Keep the hand still above the bare valve stem: the smallest task on the hand."""
  scene = "valve0"
  config_class = HoldConfig
  summary = "keep the hand still"
  # settings none of ours has, so that they can only come from this declaration
  fast_physics = dict(n_substeps=4, solver_iterations=3)
  motion = scripted.Motion(scripted.finger_roll, dict(stroke_s=0.5), leap_direction=-1.0)

  def bind(self, model):
    self.hand = common.HandJoints(model)

  def initial_state(self, rng):
    return self.hand.start_qpos(rng, self.config.hand_noise), self.hand.zero_qvel(), {}

  def observation(self, view, info):
    return view.qpos[self.hand.qpos]

  def reward_terms(self, prev, view, info):
    return {"still": -jnp.sum(jnp.abs(view.qpos[self.hand.qpos] - prev.qpos[self.hand.qpos]))}

  def success(self, view, info):
    return jnp.zeros(())


@pytest.fixture(autouse=True)
def registry_restored(monkeypatch):
  """The tasks these tests register are forgotten after each (the registry is per process)."""
  monkeypatch.setattr(registry, "REGISTRY", dict(registry.REGISTRY))


def test_a_task_registered_as_ours_trains_with_its_own_physics_and_motion(tmp_path, monkeypatch):
  assert registry.register("hold", Hold, summary="hold still") == "hold"
  built, make_envs = [], registry.make_envs

  def recorded(config):  # the envs the run is trained on, as the registry built them
    envs = make_envs(config)
    built.extend(envs)
    return envs

  monkeypatch.setattr(registry, "make_envs", recorded)
  assert cli.main(["train", "--tasks", "hold", *TINY, "--out", str(tmp_path / "run")]) == 0
  (env,) = built  # the default profile, "fast": the task's own settings
  assert (env.task.config.n_substeps, env.task.config.solver_iterations) == (4, 3)
  assert env.mj_model.opt.timestep == pytest.approx(0.01)
  assert registry.physics_overrides("hold", "reference") == {}
  assert env.task.motion == Hold.motion
  np.testing.assert_array_equal(env.task.motion.actions(7, env.dt), scripted.finger_roll(7, env.dt, stroke_s=0.5))
  np.testing.assert_array_equal(env.task.motion.actions(7, env.dt, "leap16"),
                                scripted.leap_sweep(7, env.dt, direction=-1.0))
  assert registry.entry("hold").summary == "hold still"


# the fast profile each of our tasks declares (studies/physics_study.py, docs/BENCHMARKS.md):
# a declaration lost would run the reference, twice as slow, and change no number here else
EIGHT_MS, EIGHT_MS_STIFF = dict(n_substeps=5), dict(n_substeps=5, refsafe=False)
FAST = {"valve0": EIGHT_MS_STIFF, "valve1": EIGHT_MS_STIFF, "valve2": EIGHT_MS_STIFF,
        "valve3": EIGHT_MS_STIFF, "valve_cylinder": EIGHT_MS_STIFF, "valve_cw": EIGHT_MS_STIFF,
        "valve_goal": EIGHT_MS_STIFF, "valve_goal_dense": EIGHT_MS_STIFF, "dice": EIGHT_MS,
        "dice_full": EIGHT_MS, "screw": EIGHT_MS, "screw_topdown": EIGHT_MS, "weight_pull": {}}


def test_our_tasks_declare_the_fast_physics_the_study_chose():
  # the names our modules declare: another test file may have added tasks in this process
  ours = [name for family in registry.FAMILIES for name in family.TASKS]
  assert {name: registry.physics_overrides(name, "fast") for name in ours} == \
      {**FAST, **{name: {} for name in planted.TASKS}}
  assert all(registry.physics_overrides(name, "reference") == {} for name in ours)


@pytest.mark.parametrize("task, default_config, message", [
    (HoldConfig, None, "is not a Task class"),
    (3, None, "is not a Task class"),
    (planted.PlantedEnv, None, "an Env class is registered with its default_config"),
    (toy_env.TOY_TASKS["a"], HoldConfig, "a function that makes an env has no default_config"),
])
def test_a_wrong_registration_is_one_line(task, default_config, message):
  with pytest.raises(ValueError, match=message) as err:
    registry.register("wrong", task, default_config)
  assert "\n" not in str(err.value)
  assert "wrong" not in registry.REGISTRY


def test_each_kind_registers_once_and_a_taken_name_is_refused():
  make = toy_env.TOY_TASKS["a"]
  for task, default_config in ((Hold, None), (planted.PlantedEnv, planted.default_config), (make, None)):
    name = f"again_{len(registry.REGISTRY)}"
    assert registry.register(name, task, default_config) == name == registry.register(name, task, default_config)
  with pytest.raises(ValueError, match="a task named 'valve0' is registered already"):
    registry.register("valve0", make)
  registry.register("not_an_env", lambda: HoldConfig())
  with pytest.raises(ValueError, match="returned HoldConfig, not an env"):
    registry.make("not_an_env")
