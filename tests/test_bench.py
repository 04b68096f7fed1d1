"""`discosyn bench`: one row per backend and batch; its raw-MuJoCo limit steps the same
trajectories as the env it is the limit of; bad input is exit 2."""

import numpy as np
import pytest

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


def test_wheels_travel_in_parts_and_join_only_whole(tmp_path):
  """benchmarks/gpu/wheel_parts.py: parts no larger than asked, a large wheel cut into
  pieces, joined back byte for byte; a part not yet arrived is named, nothing installed."""
  from benchmarks.gpu import wheel_parts

  wheels, parts, rng = tmp_path / "whl", tmp_path / "parts", np.random.default_rng(0)
  wheels.mkdir()
  sizes = {"big-1.0-py3-none-any.whl": 2_500, "mid-1.0-py3-none-any.whl": 700,
           "small-1.0-py3-none-any.whl": 200}
  for name, size in sizes.items():
    (wheels / name).write_bytes(rng.bytes(size))
  folders = wheel_parts.split(wheels, parts, 1_000)
  assert len(folders) == 4  # the big one in 3 pieces; mid and small share the last
  assert all(sum(f.stat().st_size for f in folder.iterdir() if f.name != wheel_parts.MANIFEST)
             <= 1_000 for folder in folders)
  moved = tmp_path / "later"
  folders[1].rename(moved)  # one part still to come
  with pytest.raises(ValueError, match="1 of the wheels' pieces have not arrived: "
                                       "big-1.0-py3-none-any.whl.piece01"):
    wheel_parts.join(parts, tmp_path / "joined")
  assert not (tmp_path / "joined").exists()
  moved.rename(folders[1])
  joined = wheel_parts.join(parts, tmp_path / "joined")
  assert sorted(p.name for p in joined) == sorted(sizes)
  for p in joined:
    assert p.read_bytes() == (wheels / p.name).read_bytes()
