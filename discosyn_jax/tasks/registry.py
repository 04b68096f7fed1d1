"""The task registry: `make(name)` builds a task's environment, `make_envs(config)` those of a
config's tasks. It knows environments only: the Trainer on them is assembled by
discosyn_jax/tasks/assemble.py. Reached as `tasks.make`, ... through
discosyn_jax/tasks/__init__.py."""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import pathlib
from typing import Callable

from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env

from discosyn_jax.checks import BadInput
from discosyn_jax.env.settings import PHYSICS
from discosyn_jax.env import hands
from discosyn_jax.env.hand_env import HandEnv
from discosyn_jax.env.task import Task, TaskConfig, TaskError, label, traceback_frames  # noqa: F401
from discosyn_jax.run import jax_setup
from discosyn_jax.tasks import dice, planted, screw, valve, valve_goal, weight_pull
from discosyn_jax.tasks.sets import TASK_SETS


@dataclasses.dataclass(frozen=True)
class Entry:
  task: Callable[[TaskConfig], Task]  # for a pure-JAX env: the env's config, as it is
  default_config: Callable[..., TaskConfig]
  summary: str
  # what `make` builds around the task: the hand on a physics backend, or a pure-JAX env
  env: Callable[..., Env] = HandEnv


def _planted(index: int, slack: bool, paid_within: float = 0.0, excursion: float = 0.0) -> Entry:
  what = "only the error inside the span counts" if slack else "the whole error counts"
  if paid_within:
    what += f"; paid only within {paid_within:g} of a typical target"
  summary = f"reach a posture in plane {index} of the planted 3-D span; {what}"
  if excursion:
    summary = (f"reach beyond {excursion:g} along the first axis of plane {index} of the "
               "planted 3-D span; paid nothing short of it")
  return Entry(lambda config: config,  # the env is built from the config itself
               lambda **kw: planted.default_config(index=index, slack=slack, paid_within=paid_within,
                                                   excursion=excursion, **kw),
               summary, env=planted.PlantedEnv)


# planted_found3: no reward until the error is below 0.7 of a typical target's size; the
# initial decoder's noise (std 0.3 on 20 actuators) alone is larger, so the task is first
# paid once the dense tasks have narrowed it (std ~0.2: a quarter of the steps at the target)
PAID_WITHIN = 0.7
# planted_reach3: paid only where the action reaches 1.0 along the task's direction: within
# what plane 2's dense targets ask along it (up to 1.46; planes 0 and 1: 0.40, 0.91), so a
# decoder serving the dense tasks reaches it; at the start 1.8-2.0 % of PPO's samples and
# 0.1-8 % of the synergy preset's (seeds 0-2) reach it, set before any run (2026-12-06)
REACH = 1.0
# planted_far3: the same task reaching 1.4, near the largest the dense targets ask along its
# direction (1.46), which a bounded z gives only near a corner of its box: at the start
# 0.15 % of PPO's samples, 0-0.75 % of the synergy preset's. Set after planted_reach3 was
# found at once by every synergy run (0.03-0.13 M env steps, 2026-12-06), before any run of it
REACH_FAR = 1.4
REGISTRY: dict[str, Entry] = {
    "valve0": Entry(valve.Valve, lambda **kw: valve.default_config(arms=0, **kw),
                    "turn a bare vertical stem counter-clockwise"),
    "valve1": Entry(valve.Valve, lambda **kw: valve.default_config(arms=1, **kw),
                    "turn a one-armed (L) valve counter-clockwise"),
    "valve2": Entry(valve.Valve, lambda **kw: valve.default_config(arms=2, **kw),
                    "turn a two-armed (T) valve counter-clockwise"),
    "valve3": Entry(valve.Valve, lambda **kw: valve.default_config(arms=3, **kw),
                    "turn a three-armed valve counter-clockwise"),
    # task set #2 (with valve3)
    "dice": Entry(dice.Dice, dice.default_config,
                  "palm up: turn a free cube about the palm normal to a goal angle"),
    "weight_pull": Entry(weight_pull.WeightPull, weight_pull.default_config,
                         "lift a weight by pulling up the rope tied to it"),
    "screw": Entry(screw.Screw, screw.default_config,
                   "roll a horizontal screwdriver with the fingers to drive it in"),
    # unseen tasks (learned with a frozen synergy decoder)
    "valve_cylinder": Entry(valve.Valve, lambda **kw: valve.default_config(shape="wheel", **kw),
                            "turn a round wheel valve counter-clockwise"),
    "valve_cw": Entry(valve.Valve, lambda **kw: valve.default_config(
                          arms=3, direction=-1.0, success_turn=1.2, **kw),
                      "turn the three-armed valve clockwise"),
    "screw_topdown": Entry(screw.Screw, lambda **kw: screw.default_config(topdown=True, **kw),
                           "drive an upright screwdriver in, clockwise from above"),
    # the dice as first specified: any axis, within 0.1 rad, no shaping (solved by no method)
    "dice_full": Entry(dice.Dice, lambda **kw: dice.default_config(
                           goal_axis="any", goal_min_angle=0.4, success_angle=0.1,
                           progress_scale=0.0, success_bonus=0.0, **kw),
                       "palm up: turn a free cube to a random orientation (any axis, 0.1 rad)"),
    # the sparse goal valve, and its dense twin for debugging
    "valve_goal": Entry(valve_goal.GoalValve, valve_goal.default_config,
                        "turn the three-armed valve to a goal angle; reward 1 near it, else 0"),
    "valve_goal_dense": Entry(valve_goal.GoalValve, lambda **kw: valve_goal.default_config(dense=True, **kw),
                              "valve_goal with a dense reward 1 - |error| / pi (debugging)"),
    # the planted-synergy test bed (pure JAX, discosyn_jax/tasks/planted.py): one span, a plane per task
    **{f"planted{n}": _planted(n, slack=False) for n in range(4)},
    **{f"planted_slack{n}": _planted(n, slack=True) for n in range(4)},
    # a task of the bed that pays nothing until it is found (planted_found's fourth)
    "planted_found3": _planted(3, slack=False, paid_within=PAID_WITHIN),
    # a task of the bed paid only for an excursion (planted_reach's fourth)
    "planted_reach3": _planted(3, slack=False, excursion=REACH),
    "planted_far3": _planted(3, slack=False, excursion=REACH_FAR),
}

# The "fast" physics profile: each task's cheapest setting that stayed within the tolerances
# of the reference (4 ms x 10) in studies/physics_study.py (docs/BENCHMARKS.md, "Physics
# settings", 2026-12-02): 8 ms steps, the valves' contacts as stiff as at 4 ms (refsafe off;
# the screws diverge or bounce so). A task not listed keeps the reference: weight_pull's rope
# failed every cheaper setting, and the pure-JAX tasks have no physics.
_EIGHT_MS = dict(n_substeps=5)
_EIGHT_MS_STIFF = dict(n_substeps=5, refsafe=False)
FAST: dict[str, dict] = {
    **{name: _EIGHT_MS_STIFF for name in ("valve0", "valve1", "valve2", "valve3", "valve_cylinder",
                                          "valve_cw", "valve_goal", "valve_goal_dense")},
    **{name: _EIGHT_MS for name in ("dice", "dice_full", "screw", "screw_topdown")}}



def register(name: str, task: type[Task], default_config=None, summary: str = "",
             env: Callable[..., Env] = HandEnv) -> str:
  """Add a task under `name` (its config class's defaults unless `default_config` is given);
  `tasks.make(name)` and `discosyn train --tasks NAME` then build it. Returns the name."""
  if not (isinstance(task, type) and issubclass(task, Task)):
    raise BadInput(f"task {name!r}: {task!r} is not a Task class (discosyn_jax.env.task.Task)")
  missing = sorted(getattr(task, "__abstractmethods__", ()))
  if missing:
    raise BadInput(f"task {name!r}: {task.__name__} does not define {', '.join(missing)}")
  new = Entry(task, default_config or task.config_class, summary or task.summary, env)
  if REGISTRY.get(name, new) != new:
    raise BadInput(f"a task named {name!r} is registered already")
  REGISTRY[name] = new
  return name


@dataclasses.dataclass(frozen=True)
class NoSettings:
  """The config of an environment registered whole (register_env): it has no settings."""


@dataclasses.dataclass(frozen=True)
class _Whole:
  """The `env` of an Entry registered whole: `make_env()`, whatever backend or hand is asked
  for (equal for the same `make_env`, so registering it again is a no-op)."""
  make_env: Callable[[], Env]

  def __call__(self, task, **_) -> Env:
    return self.make_env()


def _as_is(config):
  return config


def register_env(name: str, make_env: Callable[[], Env], summary: str = "") -> str:
  """Add an environment of one's own under `name`, built by `make_env()` whatever the
  backend, physics or hand asked for (a pure-JAX env: the tests' toy tasks). Registering the
  same `make_env` again is a no-op; another under a taken name is refused."""
  new = Entry(_as_is, NoSettings, summary or f"{name}: an env of one's own", env=_Whole(make_env))
  if REGISTRY.get(name, new) != new:
    raise BadInput(f"a task named {name!r} is registered already")
  REGISTRY[name] = new
  return name


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
  `name`: none for "reference" (TaskConfig's own defaults: 4 ms x 10)."""
  if physics not in PHYSICS:
    raise BadInput(f"unknown physics {physics!r}; known: {', '.join(PHYSICS)}")
  entry(name)
  return dict(FAST.get(name, {})) if physics == "fast" else {}


def make(name: str, *, backend: str = "auto", physics: str = "fast", hand: str = hands.DEFAULT,
         **overrides) -> Env:
  """The environment of task `name` on `backend` ("auto", "native" or "mjx"; a pure-JAX
  task has none and ignores it, as it ignores `hand`), with the physics profile `physics`
  (env/settings.py: PHYSICS) and `hand` (discosyn_jax.env.hands.load: a shipped hand or an MJCF file).

  `overrides` replace fields of the task's default config (e.g. frictionloss=0.2).
  """
  jax_setup.setup_jax()  # once: the compile cache, and what Brax's trainers need of JAX
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
