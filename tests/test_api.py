"""The public API (`from discosyn_jax import ...`): every name it promises, a run trained,
evaluated and read through it, and the package used from a folder that holds a user's own
tasks.py and experiments/ (names the package no longer claims)."""

import os
import pathlib
import pydoc
import subprocess
import sys

import pytest

import discosyn_jax as ds

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _python(code: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
  env = {**os.environ, "PYTHONPATH": str(ROOT)}  # the checkout, as the suite imports it
  return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True,
                        env=env, timeout=300)


def test_every_public_name_resolves_and_help_shows_it():
  for name in ds.__all__:
    assert getattr(ds, name) is not None, name
  page = pydoc.render_doc(ds, renderer=pydoc.plaintext)
  for name in ("train", "evaluate", "read_run", "make_env", "load_task", "TrainConfig", "Task"):
    assert name in page
  assert ds.make_env is ds.__getattribute__("make_env")  # loaded once, then a plain attribute
  with pytest.raises(AttributeError, match="no attribute 'nope'"):
    ds.nope  # noqa: B018


def test_bad_input_is_its_own_value_error():
  assert issubclass(ds.BadInput, ValueError)
  with pytest.raises(ds.BadInput, match="no tasks given"):
    ds.TrainConfig(tasks=()).validate()


def test_importing_the_package_imports_no_jax(tmp_path):
  out = _python("import sys, discosyn_jax; print('jax' in sys.modules)", tmp_path)
  assert out.returncode == 0, out.stderr
  assert out.stdout.strip() == "False"


def test_a_users_own_tasks_and_experiments_do_not_shadow_the_package(tmp_path):
  (tmp_path / "tasks.py").write_text("raise RuntimeError('the user module was imported')\n")
  (tmp_path / "experiments").mkdir()
  (tmp_path / "experiments" / "__init__.py").write_text("raise RuntimeError('user package')\n")
  code = ("from discosyn import cli; import discosyn_jax as ds\n"
          "assert ds.TASK_SETS['set1'] == ('valve0', 'valve1', 'valve2', 'valve3')\n"
          "assert ds.preset('quickstart').tasks == ('valve2', 'valve3')\n"
          "cli.main(['tasks'])\n")
  out = _python(code, tmp_path)  # `python -c` puts the working folder first on sys.path
  assert out.returncode == 0, out.stderr
  assert "valve3" in out.stdout and "weight_pull" in out.stdout


def test_train_evaluate_and_read_a_run_through_the_api(tmp_path):
  config = ds.TrainConfig(tasks=("planted0",), decoder_init="random", num_envs=8,
                          unroll_length=5, num_minibatches=2, update_epochs=1, steps=4,
                          eval_every=2, eval_envs=4, checkpoint_every=4, backend="native",
                          policy_hidden=(8,), value_hidden=(8,), discriminator_hidden=(8,))
  seen = []
  done = ds.train(config, tmp_path / "run", progress=False, log=lambda *a: None,
                  progress_fn=lambda env_steps, row: seen.append((env_steps, row)))
  assert [steps for steps, _ in seen] == [2 * 40, 4 * 40]  # 1 task x 8 envs x 5 steps per step
  assert all(0 <= row["planted0/success"] <= 1 for _, row in seen)
  assert done["run_dir"] == tmp_path / "run"
  assert set(done["results"]) == {"planted0"}

  run = ds.read_run(tmp_path / "run")
  assert run.config == config.validate()
  assert [row["env_steps"] for row in run.evaluations] == [80, 160]
  assert run.success == {"planted0": seen[-1][1]["planted0/success"]}
  assert run.mean_success == pytest.approx(sum(r["planted0/success"] for _, r in seen) / 2)
  assert len(run.metrics) == 4
  assert run.finished and run.closing["step"] == 4 and run.labels == {}
  # the report reads the same Run, its labels added: the same figures, computed once
  from discosyn_jax.experiments import report_runs

  reported = report_runs.read(tmp_path / "run")
  assert isinstance(reported, ds.Run) and reported.metrics == run.metrics
  assert reported.final == run.at_end(3) and reported.curve == run.curve

  again = ds.evaluate(tmp_path / "run")  # the deterministic policy, the same episodes
  assert again == done["results"]
  assert set(ds.evaluate(tmp_path / "run", episodes=2)) == {"planted0"}


def test_a_runs_curve_and_action_shares_read_from_its_logs(tmp_path):
  config = ds.TrainConfig(tasks=("planted0", "planted1"), residual=0.3).validate()
  evaluations = [{"planted0/success": 0.0, "planted1/success": 0.5},
                 {"planted0/success": 1.0, "planted1/success": 0.5, "env_steps": 10}]
  metrics = [{"loss": 1.0}] + [{"residual/rho": 0.3, "planted0/action_synergy": float(i),
                                "planted0/action_residual": 0.1 * i,
                                "planted1/action_synergy": 1.0,
                                "planted1/action_residual": 0.2} for i in range(12)]
  run = ds.Run(tmp_path, config, evaluations, metrics)
  assert run.success == {"planted0": 1.0, "planted1": 0.5}
  assert run.curve == {"planted0": 0.5, "planted1": 0.5}
  assert run.mean_success == pytest.approx(0.5)
  shares = run.action_shares(last=4)  # steps 8-11
  assert shares["planted0"] == pytest.approx((9.5, 0.95))
  assert shares["planted1"] == pytest.approx((1.0, 0.2))
  assert ds.Run(tmp_path, config, evaluations, metrics[:1]).action_shares() == {}


def test_a_preset_by_name_and_a_bad_one():
  with pytest.raises(ValueError, match="unknown preset 'nope'"):
    ds.train("nope")
  assert ds.PRESETS["quickstart"] == ds.preset("quickstart")
