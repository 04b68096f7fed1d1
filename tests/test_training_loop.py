"""Around the train step: auto-reset, divergence, checkpoints and exact resume, the CLI."""

import json
import shutil

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import struct

from discosyn_jax import tasks
from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import wrappers
from discosyn_jax.run import checkpoints, owner, reading
from discosyn_jax import assemble
from discosyn_jax.training import loop
from discosyn_jax.training.trainer import Trainer
from tests.toy_env import ReachAction

TINY = dict(n_synergies=2, policy_hidden=(16, 16), value_hidden=(16, 16),
            discriminator_hidden=(16, 16), num_envs=4, unroll_length=5, num_minibatches=2,
            update_epochs=1, eval_every=0, eval_envs=2, backend="native",
            squash_z=False, decoder_init="random")  # the paper's start: no prior to compute
VALVE = TrainConfig(tasks=("valve1",), steps=4, checkpoint_every=2, **TINY)


@pytest.fixture(scope="module")
def valve_run(tmp_path_factory):
  """A 4-step run on valve1, checkpointed at steps 2 and 4."""
  run_dir = tmp_path_factory.mktemp("runs") / "straight"
  result = assemble.train(VALVE, run_dir, progress=False, log=lambda *_: None)
  return run_dir, result


def test_fresh_reset_draws_a_new_initial_state_per_episode():
  env = wrappers.for_training(ReachAction(0.0, episode_length=3))
  state = env.reset(jax.random.split(jax.random.PRNGKey(0), 4))
  first = state.obs
  step = jax.jit(env.step)
  zeros = jnp.zeros((4, 20))
  starts = [first]
  for t in range(1, 7):
    state = step(state, zeros)
    if t % 3 == 0:
      np.testing.assert_array_equal(state.done, 1.0)
      np.testing.assert_array_equal(state.info["truncation"], 1.0)
      np.testing.assert_array_equal(state.info["steps"], 0.0)
      starts.append(state.obs)
    else:
      np.testing.assert_array_equal(state.done, 0.0)
      np.testing.assert_array_equal(state.info["steps"], t % 3)
  # three episodes, three different initial observations in every env
  assert not np.allclose(starts[0], starts[1]) and not np.allclose(starts[1], starts[2])


def test_a_diverged_simulation_is_flagged_reset_and_counted():
  env = tasks.make("valve1", backend="native")
  trainer = Trainer(TrainConfig(tasks=("valve1",), **TINY), envs=[env])
  state = trainer.init()
  pipeline = jax.device_get(state.env_states[0].pipeline_state)
  # velocities MuJoCo refuses (> 1e10) in two envs' float64 states: at its next step the C
  # engine resets those simulations with a warning instead of producing NaN
  raw = np.array(pipeline.raw).view(np.float64)
  nq = env.mj_model.nq
  raw[:2, 1 + nq:1 + nq + env.mj_model.nv] = 1e11  # state layout: time, qpos, qvel, ...
  blown = pipeline.replace(raw=jnp.asarray(raw.view(np.uint32)))
  state = state.replace(env_states=(state.env_states[0].replace(pipeline_state=blown),))
  state, metrics = trainer.train_step(state)
  assert float(metrics["valve1/diverged"]) == 2.0
  assert bool(metrics["finite"])
  assert np.isfinite(np.asarray(state.env_states[0].obs)).all()

  # the env alone: the step is flagged, ends the episode and pays nothing
  single = env.reset(jax.random.PRNGKey(0))
  single = env.step(single.replace(pipeline_state=jax.tree.map(
      lambda x: jnp.asarray(x[0]), pipeline.replace(raw=raw.view(np.uint32)))), jnp.zeros(20))
  assert float(single.metrics["diverged"]) == 1.0 and float(single.done) == 1.0
  assert float(single.reward) == 0.0


def test_resume_gives_the_same_state_as_an_unbroken_run(valve_run, tmp_path):
  straight_dir, straight = valve_run
  assert (straight_dir / "final").is_dir() and (straight_dir / "checkpoints" / "2").is_dir()
  broken = tmp_path / "broken"
  assemble.train(VALVE.replace(steps=2), broken, progress=False, log=lambda *_: None)
  # the unbroken run's periodic checkpoint at step 2 holds this run's final state
  trainer = assemble.trainer(VALVE)
  jax.tree.map(np.testing.assert_array_equal,
               jax.device_get(loop.restore(trainer, straight_dir / "checkpoints" / "2")),
               jax.device_get(loop.restore(trainer, broken / "final")))
  shutil.rmtree(broken / "final")  # resume from the periodic checkpoint
  resumed = assemble.train(VALVE, broken, resume=True, progress=False, log=lambda *_: None)
  a, b = jax.device_get(straight["state"]), jax.device_get(resumed["state"])
  assert int(b.step) == 4
  # bit for bit: parameters, optimiser moments, normalisers, env physics, rng
  jax.tree.map(np.testing.assert_array_equal, a, b)
  assert straight["results"] == resumed["results"]
  lines = (broken / "metrics.jsonl").read_text().splitlines()
  assert [json.loads(l)["step"] for l in lines] == [1, 2, 3, 4]
  # the wall clock goes on across the resume: it does not restart at 0
  walls = [json.loads(l)["wall_s"] for l in lines]
  evaluated = json.loads((broken / "eval.jsonl").read_text().splitlines()[-1])["wall_s"]
  assert walls == sorted(walls) and walls[0] > 0 and evaluated >= walls[-1], (walls, evaluated)


def test_checkpoint_restores_the_whole_state(valve_run):
  run_dir, straight = valve_run
  trainer = assemble.trainer(VALVE)
  restored = loop.restore(trainer, run_dir / "final")
  jax.tree.map(np.testing.assert_array_equal, jax.device_get(straight["state"]),
               jax.device_get(restored))
  assert checkpoints.latest(run_dir) == run_dir / "final"


def test_eval_prints_the_table_training_ended_with(valve_run, capsys):
  run_dir, straight = valve_run
  assert cli.main(["eval", str(run_dir)]) == 0
  rows = [l.split() for l in capsys.readouterr().out.splitlines() if l.startswith("valve1 ")]
  r = straight["results"]["valve1"]
  assert rows == [["valve1", f"{r['success']:.1%}", f"{r['return']:.2f}"]]


def test_non_finite_training_stops_and_keeps_the_last_good_checkpoint(tmp_path):
  config = TrainConfig(tasks=("a",), steps=2, checkpoint_every=2, **{**TINY, "backend": "auto"})
  run_dir = tmp_path / "run"
  good = Trainer(config, envs=[ReachAction(0.3)])
  loop.train(good, run_dir, progress=False, log=lambda *_: None)
  bad = Trainer(config.replace(steps=4), envs=[ReachAction(np.full(20, np.nan))])
  with pytest.raises(loop.TrainingDiverged, match="non-finite .* step 3.*final"):
    loop.train(bad, run_dir, resume=True, progress=False,
               log=lambda *_: None)
  assert int(loop.restore(good, run_dir / "final").step) == 2
  assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == ["2"]


@struct.dataclass
class _Counter:  # a stand-in state: checkpoints store any pytree of arrays with a step
  step: jax.Array
  w: jax.Array


def test_periodic_checkpoints_keep_the_newest_and_final_apart(tmp_path):
  for step in range(1, 6):
    checkpoints.save(tmp_path, _Counter(jnp.asarray(step), jnp.full(3, float(step))), keep=2)
  assert sorted(p.name for p in (tmp_path / "checkpoints").iterdir()) == ["4", "5"]
  checkpoints.save(tmp_path, _Counter(jnp.asarray(6), jnp.full(3, 6.0)), keep=2, final=True)
  assert sorted(p.name for p in (tmp_path / "checkpoints").iterdir()) == ["4", "5"]
  assert checkpoints.latest(tmp_path) == tmp_path / "final"
  template = _Counter(jnp.asarray(0), jnp.zeros(3))
  np.testing.assert_array_equal(checkpoints.restore(tmp_path / "checkpoints" / "4", template).w, 4.0)


def test_force_replaces_the_run_and_only_it(tmp_path):
  run_dir, beside = tmp_path / "run", tmp_path / "beside.txt"
  beside.write_text("kept")
  old, new = TrainConfig(**TINY, steps=4), TrainConfig(**TINY, steps=9)
  run_dir.mkdir()
  config_lib.save(reading.run_config(run_dir, old, resume=False, force=False), run_dir / "config.json")
  (run_dir / "metrics.jsonl").write_text("{}\n")
  (run_dir / "checkpoints" / "2").mkdir(parents=True)
  with pytest.raises(ValueError, match="already holds a run"):
    reading.run_config(run_dir, new, resume=False, force=False)
  assert reading.run_config(run_dir, new, resume=False, force=True) == new
  with owner.Writer(run_dir) as writer:  # the old run is set aside until the new one has a checkpoint
    writer.begin(lambda: config_lib.save(new, run_dir / "config.json"), replace=True)
    assert sorted(p.name for p in run_dir.iterdir()) == ["config.json", "replaced", "writer.lock"]
    writer.keep()
  assert [p.name for p in run_dir.iterdir()] == ["config.json"]
  assert config_lib.load(run_dir / "config.json") == new
  assert beside.read_text() == "kept"
  # a folder that holds something else than a run is never deleted, --force or not
  with pytest.raises(ValueError, match="holds no run"):
    reading.run_config(tmp_path, new, resume=False, force=True)
  assert beside.read_text() == "kept"


def _fails_with_one_line(argv, capsys, match):
  assert cli.main(argv) == 2
  err = capsys.readouterr().err.strip().splitlines()
  assert len(err) == 1 and err[0].startswith("discosyn: error:") and match in err[0], err


def test_train_refuses_bad_input(tmp_path, capsys):
  out = str(tmp_path / "run")
  _fails_with_one_line(["train", "--tasks", "valve9", "--out", out], capsys, "unknown task")
  _fails_with_one_line(["train", "--synergies", "0", "--out", out], capsys, "between 1 and 20")
  _fails_with_one_line(["train", "--synergies", "21", "--out", out], capsys, "between 1 and 20")
  _fails_with_one_line(["train", "--preset", "nope", "--out", out], capsys, "unknown preset")
  _fails_with_one_line(["train", "--resume", "--out", out], capsys, "holds no run")
  _fails_with_one_line(["train", "--stop-at", "80", "--out", out], capsys, "success rate in [0, 1]")
  assert not (tmp_path / "run").exists()


def test_stop_at_ends_the_run_at_the_first_evaluation_that_reaches_it(tmp_path):
  config = VALVE.replace(steps=6, eval_every=2, checkpoint_every=0)
  logged = []
  # success >= 0 holds at any evaluation: the run ends at the first, step 2, as a whole run
  done = assemble.train(config, tmp_path / "run", progress=False, log=logged.append, stop_at=0.0)
  assert int(done["state"].step) == 2 and any("the run ends here" in line for line in logged)
  evals = [json.loads(l) for l in (tmp_path / "run" / "eval.jsonl").read_text().splitlines()]
  assert [row["step"] for row in evals] == [2]  # that evaluation is the final one, not redone
  assert len((tmp_path / "run" / "metrics.jsonl").read_text().splitlines()) == 2
  _, state = assemble.load(tmp_path / "run")
  assert int(state.step) == 2
  # a rate above any success never stops it
  done = assemble.train(config, tmp_path / "all", progress=False, log=logged.append, stop_at=1.01)
  assert int(done["state"].step) == 6


def test_a_run_is_never_silently_overwritten_or_misread(valve_run, tmp_path, capsys):
  run_dir, _ = valve_run
  before = sorted(p.name for p in run_dir.rglob("*"))
  _fails_with_one_line(["train", "--out", str(run_dir)], capsys, "already holds a run")
  _fails_with_one_line(["train", "--out", str(run_dir), "--resume", "--synergies", "3",
                        "--tasks", "valve1"], capsys, "n_synergies")
  assert sorted(p.name for p in run_dir.rglob("*")) == before

  other = tmp_path / "other"  # valve_run's checkpoint under a config it does not fit
  shutil.copytree(run_dir / "final", other / "final")
  (other / "config.json").write_text(json.dumps(VALVE.replace(policy_hidden=(8, 8)).to_dict()))
  _fails_with_one_line(["eval", str(other)], capsys, "does not match this config")
  (other / "config.json").write_text("{not json")
  _fails_with_one_line(["eval", str(other)], capsys, "malformed config file")


def test_cli_resume_continues_with_the_runs_own_config(valve_run, tmp_path, capsys):
  run_dir, _ = valve_run
  copy = tmp_path / "copy"  # VALVE is no preset: resuming must not fall back to one
  shutil.copytree(run_dir, copy)
  assert cli.main(["train", "--out", str(copy), "--resume", "--steps", "5", "--no-progress"]) == 0
  out = capsys.readouterr().out
  assert "evaluation at step 5" in out and "valve1 " in out
  assert len((copy / "metrics.jsonl").read_text().splitlines()) == 5


def test_the_compiled_steps_line_counts_one_task_as_a_task(tmp_path):
  config = TrainConfig(tasks=("a",), steps=1, checkpoint_every=0, closing_episodes=0, **TINY)
  logged = []
  loop.train(Trainer(config, envs=[ReachAction(0.5)]), tmp_path / "run", progress=False,
             log=logged.append)
  (line,) = [l for l in logged if l.startswith("train step compiled in")]
  assert line.endswith("; 20 env steps per train step (1 task x 4 envs x 5 steps)"), line
