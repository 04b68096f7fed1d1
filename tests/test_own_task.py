"""A task of one's own, in one file outside the package (docs/YOUR_TASK.md): it trains with
`discosyn train --tasks FILE.py:CLASS`, its runs are read again from their config, and a
task file that is wrong is refused in one line."""

import pathlib
import shutil

import pytest

from discosyn_jax import tasks
import discosyn_jax.tasks.registry as registry
from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.run import layout

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "docs" / "examples" / "knob"
TINY = ["--num-envs", "2", "--unroll-length", "4", "--minibatches", "2", "--epochs", "1",
        "--steps", "1", "--eval-envs", "2", "--eval-every", "0", "--checkpoint-every", "0",
        "--backend", "native", "--no-progress"]


@pytest.fixture(autouse=True)
def registry_restored(monkeypatch):
  """The tasks these tests register are forgotten after each (the registry is per process)."""
  monkeypatch.setattr(registry, "REGISTRY", dict(registry.REGISTRY))


def test_a_task_in_a_folder_of_its_own_trains_and_is_read_again(tmp_path, monkeypatch):
  folder = tmp_path / "mine"
  shutil.copytree(EXAMPLE, folder)
  monkeypatch.chdir(tmp_path)  # a relative FILE.py, made absolute in the run's config
  run = tmp_path / "run"
  assert cli.main(["train", "--tasks", "mine/knob_task.py:Knob", "valve0", *TINY,
                   "--out", str(run)]) == 0
  spec = f"{folder / 'knob_task.py'}:Knob"
  assert config_lib.load(run / layout.CONFIG_FILE).tasks == (spec, "valve0")
  env = tasks.make(spec)
  assert (env.observation_size, env.action_size) == (27, 20)
  monkeypatch.delitem(tasks.REGISTRY, spec)  # as in a new process: loaded from the config
  monkeypatch.chdir(folder)
  assert cli.main(["eval", str(run), "--episodes", "2"]) == 0
  assert spec in tasks.REGISTRY


BROKEN = {
    "missing.py:Knob": "no task file missing.py",
    "knob_task.py:Door": "knob_task.py defines no Door",
    "knob_task.py": "a task of one's own is FILE.py:CLASS or MODULE:CLASS",
    "lazy.py:Lazy": "Lazy does not define observation, reward_terms, success",
    "flat.py:Flat": "Flat.observation returns shape (3, 9), not one vector",
    "notask.py:KnobConfig": "is not a Task class",
}


@pytest.mark.parametrize("spec", BROKEN)
def test_a_wrong_task_file_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys, spec):
  shutil.copytree(EXAMPLE, tmp_path, dirs_exist_ok=True)
  source = (EXAMPLE / "knob_task.py").read_text()
  (tmp_path / "lazy.py").write_text(source.replace("class Knob(Task):", "class Lazy(Task):")
                                    .split("  def observation")[0])
  (tmp_path / "flat.py").write_text("import jax.numpy as jnp\nfrom knob_task import Knob\n\n\n"
                                    "class Flat(Knob):\n  def observation(self, view, info):\n"
                                    "    return jnp.zeros((3, 9))\n")
  (tmp_path / "notask.py").write_text(source)
  monkeypatch.chdir(tmp_path)
  monkeypatch.syspath_prepend(str(tmp_path))
  run = tmp_path / "run"
  assert cli.main(["train", "--tasks", spec, *TINY, "--out", str(run)]) == 2
  err = capsys.readouterr().err.strip().splitlines()
  assert len(err) == 1 and BROKEN[spec] in err[0], err
  assert not run.exists()


def test_register_gives_a_short_name_and_refuses_a_second_task_under_it(monkeypatch):
  spec = tasks.load(f"{EXAMPLE / 'knob_task.py'}:Knob")
  knob = tasks.entry(spec).task
  assert tasks.register("knob", knob) == "knob" == tasks.register("knob", knob)  # idempotent
  assert tasks.make("knob", backend="native").observation_size == 27
  with pytest.raises(ValueError, match="a task named 'valve0' is registered already"):
    tasks.register("valve0", knob)
  assert tasks.label(spec) == "Knob" and tasks.label("valve0") == "valve0"


OWN_SET = EXAMPLE.parent / "own_set" / "own_set.py"


def _hold(env, **actions):
  """A policy holding every finger straight (J1 at its limit), the other joints mid-range,
  and these actuators at these actions: a deliberate motion of the example's tasks."""
  import jax.numpy as jnp
  import numpy as np

  from discosyn_jax.env import hands

  names = [a.removeprefix("A_") for a in hands.actuators("shadow20")]
  action = np.where([n.endswith(("J1", "J2")) for n in names], -1.0, 0.0)
  for joint, value in actions.items():
    for finger in ("FF", "MF", "RF", "LF"):
      action[names.index(finger + joint)] = value
  return lambda t, key, batch: jnp.broadcast_to(jnp.asarray(action, jnp.float32), (batch, env.action_size))


@pytest.mark.parametrize("cls, deliberate, success", [
    ("Press", dict(J2=0.4), 1.0),  # fingers bent at the knuckles: the button held down
    ("Rake", dict(J2=1.0, J1=1.0), 0.1),  # fingers curled back over the puck
    ("RakeFar", dict(J2=1.0, J1=1.0), 0.2)])  # the same, 9 cm: 0.25 (the neutral posture 0)
def test_the_own_task_set_is_solved_by_a_deliberate_motion_not_by_chance(cls, deliberate, success):
  """The example task set (docs/examples/own_set/) is well posed: a deliberate motion
  succeeds where a uniform random policy rarely does (docs/YOUR_TASK.md has the figures)."""
  import jax

  from discosyn_jax.env import rollouts

  env = tasks.make(tasks.load(f"{OWN_SET}:{cls}"), backend="native")
  keys = jax.random.split(jax.random.PRNGKey(0), 32)
  uniform = lambda t, key, batch: jax.random.uniform(key, (batch, env.action_size), minval=-1, maxval=1)
  chance = float(rollouts.run_episode(env, keys, uniform)[1].metrics["success"][-1].mean())
  done = float(rollouts.run_episode(env, keys[:8], _hold(env, **deliberate))[1].metrics["success"][-1].mean())
  assert chance <= 0.15 and done >= success and done > chance


def test_a_task_given_by_its_path_keeps_the_printed_tables_columns(capsys):
  """The evaluation table and the demo's name a task of one's own by its class: its path
  would push the columns apart."""
  from discosyn_jax.config import TrainConfig
  from discosyn_jax.training import evaluation

  spec = f"{EXAMPLE.parent / 'own_set' / 'own_set.py'}:Press"
  results = {spec: {"success": 0.5, "return": 1.25}, "valve0": {"success": 1.0, "return": -3.5}}
  _, *table = evaluation.format_table(results, 10, TrainConfig()).splitlines()
  assert [line.split()[0] for line in table] == ["task", "Press", "valve0"]
  assert len({len(line) for line in table}) == 1
  assert cli.main(["demo", spec, "valve0", "--batch", "2", "--backend", "native"]) == 0
  _, *table = capsys.readouterr().out.splitlines()
  assert [line.split()[0] for line in table] == ["task", "Press", "valve0"]
  assert len({len(line) for line in table}) == 1
