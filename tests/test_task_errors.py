"""A bug in a task's own file (docs/YOUR_TASK.md) is one line that points at it, exit status 2:
an exception its code raises names the task, its function, the file and line and the
exception (DISCOSYN_TRACEBACK=1 shows the whole traceback); a NaN or infinity in its values
names the task, the value and where it starts (the prior's measurement, a train step). A new
run leaves nothing behind; a run that made checkpoints keeps them and names the last.

Each case is the one task file below with one bug planted: a slider that drifts at 1 m/s,
away from the hand, so that where its reward goes NaN (`nan_after`) is a known train step."""

import pathlib

import pytest

from discosyn import cli
import discosyn_jax.tasks.registry as registry
from discosyn_jax import tasks

SCENE = """<mujoco model="slider">
  <worldbody>
    <body name="slider" pos="0.3 -0.04 0.1">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.02 0.02 0.02" contype="0" conaffinity="0" mass="0.1"/>
    </body>
  </worldbody>
</mujoco>
"""

TASK = """import dataclasses
import pathlib

import jax.numpy as jnp

from discosyn_jax.env.task import Task, TaskConfig
from discosyn_jax.tasks import common


@dataclasses.dataclass(frozen=True)
class SliderConfig(TaskConfig):
  episode_length: int = 40
  n_substeps: int = 2
  nan_after: float = 1e9  # m: the reward term "far" is NaN beyond


class Slider(Task):
  scene = pathlib.Path(__file__).with_name("slider.xml")
  config_class = SliderConfig

  def edit_spec(self, spec):
    spec.joint("slide").frictionloss = 0.0

  def bind(self, model):
    self.hand = common.HandJoints(model)
    self.qpos, self.qvel = common.joint_address(model, "slide")

  def initial_state(self, rng):
    qvel = self.hand.zero_qvel().at[self.qvel].set(1.0)
    return self.hand.start_qpos(rng, self.config.hand_noise), qvel, {}

  def observation(self, view, info):
    return jnp.concatenate([view.qpos[self.hand.qpos], view.qpos[self.qpos][None]])

  def reward_terms(self, prev, view, info):
    x = view.qpos[self.qpos]
    return {"progress": x - prev.qpos[self.qpos],
            "far": jnp.where(x > self.config.nan_after, jnp.nan, 0.0)}

  def success(self, view, info):
    return (view.qpos[self.qpos] > 0.5).astype(jnp.float32)
"""

TINY = ["--num-envs", "2", "--unroll-length", "4", "--minibatches", "2", "--epochs", "1",
        "--steps", "1", "--eval-envs", "2", "--eval-every", "0", "--checkpoint-every", "0",
        "--backend", "native", "--physics", "fast", "--no-progress"]
HINT = "(DISCOSYN_TRACEBACK=1 shows the whole traceback)"


@pytest.fixture(autouse=True)
def registry_restored(monkeypatch):
  """The tasks these tests load are forgotten after each (the registry is per process)."""
  monkeypatch.setattr(registry, "REGISTRY", dict(registry.REGISTRY))


def planted(folder: pathlib.Path, old: str = "", new: str = "") -> tuple[pathlib.Path, str]:
  """The task file with `old` replaced by `new` in `folder`, and the text of its first line
  that `new` changed."""
  assert TASK.count(old) == 1
  (folder / "slider.xml").write_text(SCENE)
  path = folder / "slider.py"
  path.write_text(TASK.replace(old, new))
  return path, new.strip().splitlines()[0] if new else ""


def line_of(path: pathlib.Path, text: str) -> int:
  return [n for n, line in enumerate(path.read_text().splitlines(), 1) if text in line][0]


def train(capfd, path: pathlib.Path, run: pathlib.Path, *flags: str) -> tuple[int, list[str]]:
  """`discosyn train` of the task, and what it printed on stderr (the process's own: MuJoCo
  C's warnings would be there too)."""
  code = cli.main(["train", "--tasks", f"{path}:Slider", *TINY, *flags, "--out", str(run)])
  return code, capfd.readouterr().err.strip().splitlines()


# function -> (old, new, exception): a bug in that function of the task
RAISES = {
    "edit_spec": ('spec.joint("slide")', 'spec.joint("slider")', "AttributeError"),
    "bind": ('joint_address(model, "slide")', 'joint_address(model, "nojoint")', "KeyError"),
    "initial_state": (".set(1.0)", ".set(jnp.ones(3))", "ValueError"),
    "observation": ("view.qpos[self.qpos][None]]", "view.qpos[self.qpos]]", "TypeError"),
    "success": ("return (view.qpos[self.qpos] > 0.5).astype(jnp.float32)",
                "return float(view.qpos[self.qpos] > 0.5)", "ConcretizationTypeError"),
    # traced with the step only (reset does not call it): in the new run's train step
    "terminated": ("  def success", "  def terminated(self, view, info):\n"
                   "    return (view.qpos[self.qpos] > self.config.limit).astype(jnp.float32)\n\n"
                   "  def success", "AttributeError"),
}


@pytest.mark.parametrize("function", RAISES)
def test_an_exception_in_a_task_function_is_one_line_naming_it(tmp_path, capfd, function):
  old, new, exception = RAISES[function]
  path, changed = planted(tmp_path, old, new)
  text = changed if function != "terminated" else "self.config.limit"
  run = tmp_path / "run"
  code, err = train(capfd, path, run, "--decoder-init", "random")
  assert code == 2 and len(err) == 1, err
  assert err[0].startswith(f"discosyn: error: task Slider: {function} failed at "
                           f"{path}:{line_of(path, text)}: {exception}"), err
  assert err[0].endswith(HINT)
  assert not run.exists()


# a file that fails while it is run (at import), and the start of its one line
LOAD_FAILS = {
    "a name error": ("import dataclasses\n", "import dataclasses\nundefined_name\n",
                     "NameError: name 'undefined_name' is not defined"),
    "a syntax error": ("import dataclasses\n", "import dataclasses\ndef (:\n",
                       "SyntaxError"),
    "an older release's import": ("from discosyn_jax.tasks import common\n", "import tasks\n",
                                  "ModuleNotFoundError: No module named 'tasks' (`tasks` is now "
                                  "`discosyn_jax.tasks`"),
}


@pytest.mark.parametrize("case", LOAD_FAILS)
def test_a_task_file_that_fails_at_import_is_one_line_naming_its_line(tmp_path, capfd, case):
  old, new, expected = LOAD_FAILS[case]
  path, changed = planted(tmp_path, old, new)
  run = tmp_path / "run"
  code, err = train(capfd, path, run)
  assert code == 2 and len(err) == 1, err
  assert err[0].startswith(f"discosyn: error: {path}:{line_of(path, new.splitlines()[-1])}: "
                           f"{expected}"), err
  assert err[0].endswith(HINT)
  assert not run.exists()


def test_the_whole_traceback_on_request(tmp_path, capfd, monkeypatch):
  path, changed = planted(tmp_path, *RAISES["bind"][:2])
  monkeypatch.setenv("DISCOSYN_TRACEBACK", "1")
  code, err = train(capfd, path, tmp_path / "run")
  assert code == 2 and err[0] == "Traceback (most recent call last):"
  assert f'  File "{path}", line {line_of(path, changed)}, in bind' in err
  assert err[-1].startswith("discosyn: error: task Slider: bind failed at") and HINT not in err[-1]


def test_a_hand_whose_joints_a_task_binds_is_named_too(tmp_path, capfd):
  """A task that binds our hand's wrist builds on our hand; on a hand without one, its
  line names the hand as well."""
  path, changed = planted(tmp_path, "    self.qpos, self.qvel =",
                          '    self.wrist = common.joint_address(model, "hand/WRJ1")\n'
                          "    self.qpos, self.qvel =")
  assert tasks.make(tasks.load(f"{path}:Slider"), backend="native").action_size == 20
  hand = tmp_path / "pincer.xml"
  hand.write_text("""<mujoco><worldbody><body name="palm">
    <geom type="box" size="0.03 0.01 0.04" conaffinity="1"/><site name="palm_center" pos="0 -0.01 0"/>
    <body name="finger" pos="0 0 0.05"><joint name="f1" axis="1 0 0" range="0 1.5"/>
      <geom type="capsule" size="0.01 0.03" pos="0 0 0.03" conaffinity="1"/></body>
  </body></worldbody>
  <actuator><position joint="f1" kp="1" ctrlrange="0 1.5"/></actuator></mujoco>""")
  run = tmp_path / "run"
  code, err = train(capfd, path, run, "--hand", str(hand))
  assert code == 2 and len(err) == 1, err
  assert err[0].startswith(f"discosyn: error: task Slider on hand {hand}: bind failed at "
                           f"{path}:{line_of(path, changed)}: KeyError: \"Invalid name 'hand/WRJ1'. "
                           "Valid names: ['hand/f1', 'slide']"), err
  assert not run.exists()


def test_a_nan_reward_is_named_by_the_prior_before_training(tmp_path, capfd):
  path, _ = planted(tmp_path, "nan_after: float = 1e9", "nan_after: float = -1e9")
  run = tmp_path / "run"
  code, err = train(capfd, path, run, "--decoder-init", "reward")
  assert code == 2 and err == [
      "discosyn: error: task Slider: reward term 'far' is non-finite (NaN or infinite) at the "
      "states the reward prior is measured at (the decoder's start, before training)"]
  assert not run.exists()


NAN = {  # what goes NaN from the first step -> (old, new)
    "reward term 'far'": ("nan_after: float = 1e9", "nan_after: float = -1e9"),
    "its observation": ("view.qpos[self.qpos][None]]", "view.qpos[self.qpos][None] * jnp.nan]"),
    "its success": ("(view.qpos[self.qpos] > 0.5).astype(jnp.float32)",
                    "jnp.log(view.qpos[self.qpos] - 10.0)"),
}


@pytest.mark.parametrize("what", NAN)
def test_a_nan_at_the_first_step_is_named_and_the_new_run_removed(tmp_path, capfd, what):
  path, _ = planted(tmp_path, *NAN[what])
  run = tmp_path / "run"
  code, err = train(capfd, path, run, "--decoder-init", "random")
  assert code == 2 and err == [
      f"discosyn: error: task Slider: {what} is non-finite (NaN or infinite) at train step 1; "
      "training stopped; the new run made no checkpoint and was removed"]
  assert not run.exists()


def test_a_nan_mid_training_is_named_and_the_last_checkpoint_kept(tmp_path, capfd):
  """The slider passes 0.34 m in control step 9: train step 3 of 4 control steps."""
  path, _ = planted(tmp_path, "nan_after: float = 1e9", "nan_after: float = 0.34")
  run = tmp_path / "run"
  code, err = train(capfd, path, run, "--decoder-init", "random", "--steps", "6",
                    "--checkpoint-every", "2")
  assert code == 2 and err == [
      "discosyn: error: task Slider: reward term 'far' is non-finite (NaN or infinite) at train "
      f"step 3; training stopped; the last good checkpoint is {run / 'checkpoints' / '2'}"]
  assert sorted(p.name for p in (run / "checkpoints").iterdir()) == ["2"]
