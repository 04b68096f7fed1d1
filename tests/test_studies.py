"""The studies beside the package (studies/README.md): each still imports and answers
--help on today's code, and those that run in seconds run on a tiny setting and print
their table. (same_logs has its own tests, test_same_logs.py.)"""

import importlib
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
STUDIES = sorted(p.stem for p in (ROOT / "studies").glob("*.py") if p.stem != "__init__")


@pytest.fixture(scope="module", autouse=True)
def _checkout_on_path():
  sys.path.insert(0, str(ROOT))  # studies/ lives in the repository, not in the package
  yield
  sys.path.remove(str(ROOT))


def study(name):
  return importlib.import_module(f"studies.{name}")


def test_the_index_names_every_study():
  index = (ROOT / "studies" / "README.md").read_text()
  assert STUDIES and all(f"{name}.py" in index for name in STUDIES)


@pytest.mark.parametrize("name", STUDIES)
def test_every_study_imports_and_answers_help(name, capsys):
  with pytest.raises(SystemExit) as stop:
    study(name).main(["--help"])
  assert stop.value.code == 0
  assert "usage:" in capsys.readouterr().out


def test_the_physics_study_measures_a_setting(capsys):
  study("physics_study").main(["--tasks", "valve0", "--settings", "ref", "--batch", "2",
                               "--steps", "2", "--repeats", "1", "--episodes", "2",
                               "--long-episodes", "1", "--long-steps", "4"])
  out = capsys.readouterr().out
  assert "| valve0 | ref |" in out and "cheapest faithful setting ref" in out


def test_the_task_calibration_runs_a_policy(capsys):
  study("task_calibration").main(["--tasks", "valve3", "--episodes", "2", "--policies", "random"])
  assert "valve3" in capsys.readouterr().out


def test_the_valve_calibration_runs_a_valve(capsys):
  study("valve_calibration").main(["--valves", "valve0", "--episodes", "2"])
  assert "valve0" in capsys.readouterr().out


def test_the_residual_schedule_study_refuses_a_preset_without_a_residual(capsys, tmp_path):
  with pytest.raises(SystemExit) as stop:
    study("residual_schedule").main(["--preset", "set2-disco6-linear", "--out", str(tmp_path)])
  assert stop.value.code == 2
  assert "set2-disco6-linear has no residual" in capsys.readouterr().err
  assert not any(tmp_path.iterdir())  # nothing trained, nothing written


def test_the_set2_lag_study_reads_when_a_run_finds_a_task(capsys):
  """Its 'found' is the first evaluation at 0.8 or above, in the task's env steps, as the
  record's eval.jsonl has it; PPO's heads get no discriminator bonus."""
  import json

  folder = ROOT / "docs" / "results" / "confirm-late-residual"
  lag = study("set2_lag")
  runs = {r.path.name: r for r in lag.runs([folder])}
  ppo = runs["set2-ppo-seed3"]
  rows = [json.loads(line) for line in (ppo.path / "eval.jsonl").read_text().splitlines()]
  first = next(r for r in rows if r["weight_pull/success"] >= 0.8)
  config = ppo.config
  assert lag.found_at(ppo, "weight_pull") == first["step"] * config.num_envs * config.unroll_length
  summary = lag.summary(ppo, "weight_pull", 500_000)
  assert summary["bonus"] == 0.0 and summary["h_start"] > 0
  lag.main([str(folder), "--tasks", "weight_pull"])
  out = capsys.readouterr().out
  assert "| PPO | 3 |" in out and "| DiscoSyn6-L-reward | 3 |" in out
