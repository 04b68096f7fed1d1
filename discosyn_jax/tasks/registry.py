"""The task registry: `make(name)` builds a task's environment, `make_envs(config)` those of a
config's tasks. Our tasks and a task of one's own are added alike, by `register`; a task
declares its own settings (its fast physics, its scripted motion). It knows environments
only: the Trainer on them is assembled by discosyn_jax/assemble.py. Reached as
`tasks.make`, ... through discosyn_jax/tasks/__init__.py."""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import pathlib
from typing import Any, Callable

from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env

from discosyn_jax.checks import BadInput
from discosyn_jax.env.settings import PHYSICS
from discosyn_jax.env import hands
from discosyn_jax.env.hand_env import HandEnv
from discosyn_jax.env.task import Task, TaskConfig, TaskError, label, traceback_frames  # noqa: F401
from discosyn_jax.tasks import dice, planted, screw, valve, valve_goal, weight_pull
from discosyn_jax.tasks.sets import TASK_SETS


@dataclasses.dataclass(frozen=True)
class Entry:
  # the Task of a config; for an env built from its config alone: the config, as it is
  task: Callable[[TaskConfig], Task]
  default_config: Callable[[], Any]
  summary: str
  # what `make` builds around the task: the hand on a physics backend, or a pure-JAX env
  env: Callable[..., Env] = HandEnv

  @property
  def fast_physics(self) -> dict:
    """The config fields the "fast" profile sets: the Task's own (Task.fast_physics); an env
    built without a Task has no physics of ours to set."""
    return dict(self.task.fast_physics) if self.env is HandEnv else {}


REGISTRY: dict[str, Entry] = {}


def register(name: str, task, default_config: Callable[[], Any] | None = None,
             summary: str = "") -> str:
  """Add a task under `name`: the one path of our tasks and of a task of one's own alike;
  `tasks.make(name)` and `discosyn train --tasks NAME` then build it. `task` is one of
  - a Task class: the hand on a physics backend around it, its config `default_config()`
    (its config class's defaults unless given); it declares its own fast physics and
    scripted motion (Task.fast_physics, Task.motion);
  - a Brax Env class built from its config alone, `task(config, backend=, hand=)`, given its
    `default_config` (a pure-JAX env: the planted bed);
  - a function of no arguments that returns an env, whatever backend, physics or hand is
    asked for (registered whole: it has no settings).
  Registering the same again is a no-op; another under a taken name is refused. Returns the
  name."""
  new = _entry(name, task, default_config, summary)
  if REGISTRY.get(name, new) != new:
    raise BadInput(f"a task named {name!r} is registered already")
  REGISTRY[name] = new
  return name


def _entry(name: str, task, default_config, summary: str) -> Entry:
  """`register`'s Entry for `task`, or one line saying what is wrong with it."""
  if isinstance(task, type) and issubclass(task, Task):
    missing = sorted(getattr(task, "__abstractmethods__", ()))
    if missing:
      raise BadInput(f"task {name!r}: {task.__name__} does not define {', '.join(missing)}")
    return Entry(task, default_config or task.config_class, summary or task.summary)
  if isinstance(task, type) and issubclass(task, Env):
    if default_config is None:
      raise BadInput(f"task {name!r}: an Env class is registered with its default_config")
    return Entry(_as_is, default_config, summary, env=task)
  if callable(task) and not isinstance(task, type):
    if default_config is not None:
      raise BadInput(f"task {name!r}: a function that makes an env has no default_config")
    return Entry(_as_is, NoSettings, summary or f"{name}: an env of one's own", env=_Whole(task))
  raise BadInput(f"task {name!r}: {task!r} is not a Task class (discosyn_jax.env.task.Task), "
                 "an Env class or a function that makes an env")


@dataclasses.dataclass(frozen=True)
class NoSettings:
  """The config of an environment registered whole: it has no settings."""


@dataclasses.dataclass(frozen=True)
class _Whole:
  """The `env` of an Entry registered whole: `make_env()`, whatever backend or hand is asked
  for (equal for the same `make_env`, so registering it again is a no-op)."""
  make_env: Callable[[], Env]

  def __call__(self, task, **_) -> Env:
    env = self.make_env()
    if not isinstance(env, Env):
      raise BadInput(f"{getattr(self.make_env, '__name__', self.make_env)!r} returned "
                     f"{type(env).__name__}, not an env")
    return env


def _as_is(config):
  return config


def load(spec: str) -> str:
  """Register the task of `spec`, "path/to/file.py:ClassName" or "module:ClassName" (a task
  of one's own, outside this package: docs/YOUR_TASK.md), under its spec with the file's
  path made absolute, so that a run's config names it wherever the run is read again."""
  where, _, attr = spec.rpartition(":")
  if not where or not attr:
    raise BadInput(f"a task of one's own is FILE.py:CLASS or MODULE:CLASS, not {spec!r}")
  if where.endswith(".py"):
    path = pathlib.Path(where).expanduser().resolve()
    name = f"{path}:{attr}"
    if name in REGISTRY:
      return name
    if not path.is_file():
      raise BadInput(f"no task file {where}")
    module_spec = importlib.util.spec_from_file_location(f"discosyn_task_{path.stem}", path)
    module = importlib.util.module_from_spec(module_spec)
    try:
      module_spec.loader.exec_module(module)
    except Exception as err:  # the file's own code: one line that points at it
      raise TaskError(_load_failed(where, path, err)) from err
  else:
    name = spec
    if name in REGISTRY:
      return name
    try:
      module = importlib.import_module(where)
    except ImportError as err:
      raise BadInput(f"task {spec!r}: cannot import {where}: {err}") from None
  if not hasattr(module, attr):
    raise BadInput(f"{where} defines no {attr}")
  return register(name, getattr(module, attr))


# names that older releases installed at the top level, and where they live now
_MOVED_TOP = {"tasks": "discosyn_jax.tasks", "experiments": "discosyn_jax.experiments"}


def _load_failed(where: str, path: pathlib.Path, err: Exception) -> str:
  """One line for a task file that fails while it is run: where in the file, and what."""
  if isinstance(err, SyntaxError):
    return f"{where}:{err.lineno}: SyntaxError: {err.msg}"
  line = next((tb.tb_lineno for tb in reversed(list(traceback_frames(err.__traceback__)))
               if pathlib.Path(tb.tb_frame.f_code.co_filename).resolve() == path), None)
  message = next(iter(str(err).strip().splitlines()), "")
  text = f"{where}{f':{line}' if line else ''}: {type(err).__name__}{': ' + message if message else ''}"
  moved = _MOVED_TOP.get(getattr(err, "name", None) or "")
  if isinstance(err, ModuleNotFoundError) and moved:
    text += f" (`{err.name}` is now `{moved}`: `from {moved} import ...`)"
  return text


def entry(name: str) -> Entry:
  if name not in REGISTRY and ":" in name:  # a task of one's own, named in a run's config
    loaded = load(name)  # a file named relative to the working folder: known by both names
    REGISTRY.setdefault(name, REGISTRY[loaded])
  if name not in REGISTRY:
    raise BadInput(f"unknown task {name!r}; known tasks: {', '.join(REGISTRY)}")
  return REGISTRY[name]


def make_config(name: str, **overrides) -> TaskConfig:
  defaults = entry(name).default_config()
  fields = {f.name for f in dataclasses.fields(defaults)}
  unknown = sorted(set(overrides) - fields)
  if unknown:
    raise BadInput(f"task {name!r} has no setting {', '.join(unknown)}; "
                   f"its settings: {', '.join(sorted(fields))}")
  try:
    return dataclasses.replace(defaults, **overrides)
  except ValueError as err:
    raise BadInput(f"task {name!r}: {err}") from None


def physics_overrides(name: str, physics: str) -> dict:
  """The task config fields that physics profile `physics` (env/settings.py: PHYSICS) sets for task
  `name`: its own fast settings for "fast", none for "reference" (TaskConfig's own defaults:
  4 ms x 10)."""
  if physics not in PHYSICS:
    raise BadInput(f"unknown physics {physics!r}; known: {', '.join(PHYSICS)}")
  fast = entry(name).fast_physics
  return fast if physics == "fast" else {}


def make(name: str, *, backend: str = "auto", physics: str = "fast", hand: str = hands.DEFAULT,
         **overrides) -> Env:
  """The environment of task `name` on `backend` ("auto", "native" or "mjx"; a pure-JAX
  task has none and ignores it, as it ignores `hand`), with the physics profile `physics`
  (env/settings.py: PHYSICS) and `hand` (discosyn_jax.env.hands.load: a shipped hand or an MJCF file).

  `overrides` replace fields of the task's default config (e.g. frictionloss=0.2). It
  changes nothing global: a run turns the compile cache on where it is assembled
  (discosyn_jax/assemble.py), and Brax finds what it needs of JAX when it is imported
  (quiet_mjx.py).
  """
  config = make_config(name, **{**physics_overrides(name, physics), **overrides})
  try:
    task = entry(name).task(config)
  except ValueError as err:
    raise BadInput(f"task {name!r}: {err}") from None
  return entry(name).env(task, backend=backend, hand=hand)


def expand(names) -> list[str]:
  """Task names with every task set among them replaced by its tasks, in order."""
  out = []
  for name in names:
    if name in TASK_SETS:
      out += TASK_SETS[name]
    elif name in REGISTRY:
      out.append(name)
    elif ":" in name or name.endswith(".py"):  # a task of one's own
      out.append(load(name))
    else:
      raise BadInput(f"unknown task or task set {name!r}; tasks: {', '.join(REGISTRY)}; "
                     f"sets: {', '.join(TASK_SETS)}")
  return out


def sets_of(name: str) -> list[str]:
  return [s for s, names in TASK_SETS.items() if name in names]


def make_envs(config) -> list[Env]:
  """The envs of a TrainConfig's tasks, on its backend, physics and hand."""
  return [make(name, backend=config.backend, physics=config.physics, hand=config.hand)
          for name in config.tasks]


def names() -> tuple[str, ...]:
  """Every registered task's name, ours and those registered since."""
  return tuple(REGISTRY)


FAMILIES = (valve, dice, weight_pull, screw, valve_goal, planted)  # the modules of our tasks


def _register_ours() -> None:
  """Our tasks, through `register` as a task of one's own: each family module lists its own
  (TASKS: name -> task, default config, summary)."""
  for family in FAMILIES:
    for name, (task, default_config, summary) in family.TASKS.items():
      register(name, task, default_config, summary)


_register_ours()
