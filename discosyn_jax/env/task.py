"""What a task is: a scene plus pure JAX functions of the physics view.

A task never touches a backend's structures: every method below reads a `PhysicsView`
(qpos, qvel, sensors) and the task's own `info` dict, so one task code runs on both
physics backends.
"""

from __future__ import annotations

import abc
import contextlib
import dataclasses
import os
import pathlib
import types
from typing import Any, Mapping

import jax
import mujoco

from discosyn_jax import checks
from discosyn_jax.checks import BadInput
from discosyn_jax.env.settings import CONTROL_DT
from discosyn_jax.env import hands, scene, scripted
from discosyn_jax.env.physics import PhysicsView

Info = dict[str, Any]
_CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}


@dataclasses.dataclass(frozen=True)
class TaskConfig:
  """What every task has; task families subclass it with their own fields."""

  episode_length: int = 100  # control steps of 0.04 s: 4 s
  # The physics of one control step (CONTROL_DT): n_substeps MuJoCo steps of CONTROL_DT /
  # n_substeps each; the solver settings go to the model's <option>. These defaults are the
  # "reference" physics; a run's profile may override them (Task.fast_physics).
  n_substeps: int = 10
  solver_iterations: int = 8
  ls_iterations: int = 8
  cone: str = "pyramidal"  # or "elliptic"
  # False: contacts keep the 0.01 s time constant of their solref at timesteps over 5 ms,
  # where MuJoCo's refsafe would raise it to 2 x timestep (softer: deeper penetration)
  refsafe: bool = True
  hand_noise: float = 0.05  # rad, uniform noise on the initial hand joint angles

  def __post_init__(self):
    # every task's config (and every override of one): types, finite numbers, then ranges;
    # the task classes check their own fields' ranges
    checks.fields(self)
    for name in ("episode_length", "n_substeps", "solver_iterations", "ls_iterations"):
      if getattr(self, name) < 1:
        raise BadInput(f"{name} must be at least 1, not {getattr(self, name)}")
    if self.cone not in _CONES:
      raise BadInput(f"cone must be one of {', '.join(_CONES)}, not {self.cone!r}")
    if self.hand_noise < 0:
      raise BadInput(f"hand_noise must not be negative, not {self.hand_noise}")

  @property
  def timestep(self) -> float:
    return CONTROL_DT / self.n_substeps


class Task(abc.ABC):
  scene: str | pathlib.Path  # an object of xml/objects/ by name, or a task's own object MJCF file
  mount = hands.PALM_DOWN  # or hands.PALM_UP, for objects that rest on the palm
  config_class: type = TaskConfig  # a task of one's own: its config (tasks.load)
  summary: str = ""  # one line for `discosyn tasks`
  # the config fields the "fast" physics profile sets (env/settings.py: PHYSICS): a cheaper
  # setting measured within the reference's tolerances; none keeps the reference under both
  fast_physics: Mapping[str, Any] = types.MappingProxyType({})
  # the deliberate motion tried on the task (calibration, tests, scene pictures): the sweep
  # unless the task declares its own (on a task it cannot do, it only shows the hand moving)
  motion: scripted.Motion = scripted.Motion()

  def __init__(self, config: TaskConfig):
    self.config = config

  def build_model(self, hand: str | hands.Hand = hands.DEFAULT) -> mujoco.MjModel:
    """The task's scene with `hand` (hands.load), compiled."""
    spec = scene.load_spec(self.scene, hand, self.mount)
    option, config = spec.option, self.config
    option.timestep, option.iterations = config.timestep, config.solver_iterations
    option.ls_iterations, option.cone = config.ls_iterations, _CONES[config.cone]
    if not config.refsafe:
      option.disableflags |= mujoco.mjtDisableBit.mjDSBL_REFSAFE
    self.edit_spec(spec)
    model = spec.compile()
    self.dt = CONTROL_DT
    self.bind(model)
    return model

  def edit_spec(self, spec: mujoco.MjSpec) -> None:
    """Set config-dependent parameters of the scene before it is compiled."""

  def bind(self, model: mujoco.MjModel) -> None:
    """Look up the indices the pure functions need (called once, on the host)."""

  @abc.abstractmethod
  def initial_state(self, rng: jax.Array) -> tuple[jax.Array, jax.Array, Info]:
    """(qpos, qvel, info) of a fresh episode."""

  @abc.abstractmethod
  def observation(self, view: PhysicsView, info: Info) -> jax.Array: ...

  @abc.abstractmethod
  def reward_terms(self, prev: PhysicsView, view: PhysicsView, info: Info) -> dict[str, jax.Array]:
    """Reward of the transition prev -> view, as named terms that sum to the reward."""

  @abc.abstractmethod
  def success(self, view: PhysicsView, info: Info) -> jax.Array:
    """1.0 where the episode counts as solved if it ended in this state, else 0.0."""

  def show(self, model: mujoco.MjModel, data: mujoco.MjData, info: Info) -> None:
    """Draw an episode's own values (e.g. a goal) into `data` before it is rendered."""

  def terminated(self, view: PhysicsView, info: Info) -> jax.Array:
    """1.0 where the episode ends before its time limit (e.g. a dropped object)."""
    del view, info
    return jax.numpy.zeros(())


class TaskError(BadInput):
  """An exception raised by a task's own code, in one line: the task, its function, the
  file and line where it was raised, and the exception (its __cause__, with the traceback)."""


@contextlib.contextmanager
def own_code(task: Task, hand: hands.Hand | None = None):
  """Around calls into a task's functions (building its scene, tracing its reset and step):
  an exception raised in the task's own file becomes a TaskError that says where. Costs
  nothing once traced: it runs in Python only, at build and trace time."""
  try:
    yield
  except TaskError:
    raise
  except Exception as err:
    line = _blame(task, hand, err)
    if line is None:  # not the task's code: ours, MuJoCo's or JAX's, as it is
      raise
    raise TaskError(line) from err


def _files(task: Task) -> set[str]:
  """The files that define the functions of the task's class and of its own base classes
  (a task may inherit from another file of its author's). Read from the functions' code:
  `inspect.getsourcefile` finds no file for a class whose module is not in sys.modules, as a
  task file's (tasks.load runs it without adding it there)."""
  files = set()
  for cls in type(task).__mro__:
    if cls is not Task and issubclass(cls, Task):
      for value in vars(cls).values():
        code = getattr(getattr(value, "__func__", value), "__code__", None)
        if code is not None:
          files.add(os.path.realpath(code.co_filename))
  return files


def traceback_frames(tb):
  """A traceback's entries, outermost first."""
  while tb is not None:
    yield tb
    tb = tb.tb_next


def label(name: str) -> str:
  """A task's name as a file name: a task of one's own ("file.py:Slider") by its class."""
  return name.rpartition(":")[2]


def _blame(task: Task, hand: hands.Hand | None, err: Exception) -> str | None:
  """The line of an exception whose traceback passes through the task's files: the
  function of the task it left (the outermost such frame) and where it was raised there
  (the innermost); None where no frame is the task's."""
  files = _files(task)
  frames = [tb for tb in traceback_frames(err.__traceback__)
            if os.path.realpath(tb.tb_frame.f_code.co_filename) in files]
  if not frames:
    return None
  function, raised = frames[0].tb_frame.f_code.co_name, frames[-1]
  on = f" on hand {hand.name}" if hand is not None and hand.name != hands.DEFAULT else ""
  message = next(iter(str(err).strip().splitlines()), "")  # JAX's messages run on for lines
  return (f"task {type(task).__name__}{on}: {function} failed at "
          f"{raised.tb_frame.f_code.co_filename}:{raised.tb_lineno}: {type(err).__name__}"
          f"{': ' + message if message else ''}")


def not_finite(task: str, parts: list[str], where: str) -> str:
  """One line naming a task's values that are NaN or infinite `where`: `parts` are
  "observation", "success", "reward/TERM" (a reward term) or "reward" (an env without terms)."""
  names = [f"reward term {p.removeprefix('reward/')!r}" if p.startswith("reward/") else
           "the reward" if p == "reward" else f"its {p}" for p in parts]
  verb = "is" if len(names) == 1 else "are"
  return f"task {task}: {', '.join(names)} {verb} non-finite (NaN or infinite) {where}"
