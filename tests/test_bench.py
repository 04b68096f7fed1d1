"""`discosyn bench`: one row per backend and batch; its raw-MuJoCo limit steps the same
trajectories as the env it is the limit of; bad input is exit 2."""

import numpy as np

from discosyn import cli


def test_bench_prints_a_physics_row_per_batch_and_profile(capsys):
  argv = ["bench", "--tasks", "valve1", "--batches", "2", "4", "--physics", "reference", "fast",
          "--no-train", "--repeats", "1"]
  assert cli.main(argv) == 0
  rows = [l.split("|") for l in capsys.readouterr().out.splitlines() if l.startswith("| native")]
  assert [(r[2].strip(), r[3].strip()) for r in rows] == [
      ("2", "reference"), ("2", "fast"), ("4", "reference"), ("4", "fast")]
  for r in rows:
    assert float(r[4].replace(",", "")) > 0 and float(r[5].replace(",", "")) > 0  # env/s
    assert r[7].strip() == "-"  # no training asked


def test_bench_refuses_zero_repeats(capsys):
  assert cli.main(["bench", "--repeats", "0", "--no-train"]) == 2
  assert "--repeats must be at least 1" in capsys.readouterr().err


def test_the_raw_limit_replays_the_envs_own_states_and_controls():
  from discosyn_jax import tasks
  from discosyn_jax.config import TrainConfig
  from discosyn_jax.experiments.bench import RawRollout, bench_inputs, physics_runner

  envs = tasks.make_envs(TrainConfig(squash_z=False, decoder_init="random", tasks=("valve1", "valve3"), backend="native"))
  states, actions = bench_inputs(envs, 4, 5)
  run, _ = physics_runner(envs, states, actions)
  for env, state, final in zip(envs, states, run()):
    raw = RawRollout(env, state, actions, nthread=1)
    try:
      trajectory, _ = raw()  # (batch, steps x substeps, [time, qpos, ...])
    finally:
      raw.close()
    nq = env.mj_model.nq
    assert trajectory.shape[:2] == (4, 5 * env.task.config.n_substeps)
    np.testing.assert_array_equal(raw.state[:, 1:1 + nq], np.asarray(state.pipeline_state.qpos))
    moved = np.abs(trajectory[:, -1, 1:1 + nq] - raw.state[:, 1:1 + nq]).max()
    assert moved > 1e-2  # the hand moved: the comparison below is not of two rest poses
    np.testing.assert_allclose(trajectory[:, -1, 1:1 + nq], np.asarray(final.pipeline_state.qpos),
                               atol=1e-5)
