"""A run whose writer died after its final checkpoint (killed while it drew its curves):
the kernel dropped its lock, its lock file stays. The next command that writes the run takes
the lock over in one warning, draws the missing curves and releases the lock."""

import json
import shutil
import socket
import subprocess
import sys

import pytest

from discosyn import cli
from discosyn_jax import tasks
from discosyn_jax.experiments import paper, report_runs
from discosyn_jax.run import layout, owner
from discosyn_jax import assemble
from discosyn_jax.viz import plots
from tests.fault_worker import TOY, toy_envs


@pytest.fixture
def killed_after_its_end(tmp_path, monkeypatch):
  """(run folder, dead writer's pid): a finished toy run with its curves gone and the lock
  file its dead writer left."""
  from discosyn_jax.experiments import presets

  monkeypatch.setattr(tasks.registry, "make_envs", toy_envs)
  monkeypatch.setattr(presets, "preset", lambda name: TOY)
  run_dir = tmp_path / "out" / "toy"
  assemble.train(TOY, run_dir, progress=False, log=lambda *_: None)
  assert not (run_dir / layout.LOCK).exists()  # a run that ends releases its lock
  dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                        capture_output=True, text=True, check=True)
  pid = int(dead.stdout)
  shutil.rmtree(run_dir / layout.PLOTS_DIR)
  (run_dir / layout.LOCK).write_text(json.dumps(
      {"pid": pid, "host": socket.gethostname(), "started": "2026-12-07 20:00:00 UTC"}))
  assert owner.writer_of(run_dir) is None  # no one holds it: readers read on
  assert report_runs.read(run_dir).finished
  return run_dir, pid


def assert_finished_by_this_process(run_dir, pid, err: str) -> None:
  (line,) = [l for l in err.splitlines() if l]
  assert line.startswith(f"discosyn: warning: {run_dir} was left by process {pid} on ")
  assert line.endswith("this process takes it over")
  assert all((run_dir / layout.PLOTS_DIR / name).is_file() for name in plots.CURVES)
  assert not (run_dir / layout.LOCK).exists()


def test_an_experiment_run_again_finishes_a_run_killed_after_its_final_checkpoint(
    killed_after_its_end, capsys):
  run_dir, pid = killed_after_its_end
  meta = dict(experiment="train", method="DiscoSyn2-L", set="toy", seed=0, scale="ci")
  logged = []
  paper.Train(run_dir.name, TOY, meta).settle(run_dir.parent, logged.append)
  assert_finished_by_this_process(run_dir, pid, capsys.readouterr().err)
  assert any(line.startswith("training curves: ") for line in logged)
  # done: the next time, nothing is taken over or drawn again
  drawn = (run_dir / layout.PLOTS_DIR / "success.png").stat().st_mtime_ns
  paper.Train(run_dir.name, TOY, meta).settle(run_dir.parent, logged.append)
  assert capsys.readouterr().err == ""
  assert (run_dir / layout.PLOTS_DIR / "success.png").stat().st_mtime_ns == drawn


def test_resuming_a_run_killed_after_its_final_checkpoint_draws_its_curves(killed_after_its_end, capsys):
  run_dir, pid = killed_after_its_end
  assert cli.main(["train", "--out", str(run_dir), "--resume", "--no-progress"]) == 0
  assert_finished_by_this_process(run_dir, pid, capsys.readouterr().err)


def test_a_run_a_live_process_writes_is_left_to_it(killed_after_its_end, capsys):
  run_dir, _ = killed_after_its_end
  with owner.Writer(run_dir):  # the writer, alive: it draws its curves itself
    assemble.finish(run_dir)
    assert not (run_dir / layout.PLOTS_DIR).exists()
  capsys.readouterr()
