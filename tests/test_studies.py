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


def test_the_finding_lag_study_reads_when_a_run_finds_a_task(capsys):
  """Its 'found' is the first evaluation at 0.8 or above, in the task's env steps, as the
  record's eval.jsonl has it; PPO's heads get no discriminator bonus."""
  import json

  folder = ROOT / "docs" / "results" / "confirm-late-residual"
  lag = study("finding_lag")
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


def test_the_planted_lag_study_trains_its_variants_and_reads_them(tmp_path, capsys):
  """Each variant is the planted preset with its one change, named so that the report tells
  them apart; a tiny run of two variants trains, keeps its record and is read back."""
  from discosyn_jax.experiments.method import Method

  lag = study("planted_lag")
  made = {meta["method"]: config for _, config, meta in lag.configs(list(lag.VARIANTS), [0])}
  assert set(made) == {"DiscoSyn3-L", "DiscoSyn3-L-qact", "DiscoSyn3-L-zfree", "DiscoSyn3-L-alpha2=0",
                       "DiscoSyn3-L-zfloor0.7", "DiscoSyn3-L-res0.3r200", "DiscoSyn3-L-res0.3r67s133",
                       "DiscoSyn3-L-tasknoise", "DiscoSyn3-L-tasknoise-alpha2=0",
                       "DiscoSyn3-L-tasknoise-bonuscap", "PPO"}
  assert made["DiscoSyn3-L-zfloor0.7"].z_std_floor == lag.FLOOR
  assert made["DiscoSyn3-L-tasknoise"].task_noise and made["DiscoSyn3-L-tasknoise"].alpha2 > 0
  assert made["DiscoSyn3-L-tasknoise-alpha2=0"].task_noise
  assert made["DiscoSyn3-L-tasknoise-alpha2=0"].alpha2 == 0.0
  assert made["DiscoSyn3-L-tasknoise-bonuscap"].bonus_cap
  assert made["PPO"].decoder == "identity" and made["PPO"].steps == made["DiscoSyn3-L"].steps
  assert all(Method.parse(name).name == name for name in made)
  assert made["DiscoSyn3-L-qact"].discriminator_target == "activation"
  assert not made["DiscoSyn3-L-zfree"].squash_z and made["DiscoSyn3-L-alpha2=0"].alpha2 == 0.0
  assert made["DiscoSyn3-L"].tasks[-1] == "planted_found3"
  reach = {meta["method"]: config for _, config, meta in lag.configs(["default"], [0], None,
                                                                      "planted_reach")}
  assert reach["DiscoSyn3-L"].tasks[-1] == "planted_reach3"
  lag.main(["--seeds", "0", "--variants", "default", "no-bonus", "--steps", "4",
            "--out", str(tmp_path)])
  out = capsys.readouterr().out
  assert "| DiscoSyn3-L | 0 |" in out and "| DiscoSyn3-L-alpha2=0 | 0 | " in out
  no_bonus = out.split("| DiscoSyn3-L-alpha2=0 | 0 | ")[1].splitlines()[0]
  assert no_bonus.endswith("| 0.0000 |")  # alpha2 = 0: no bonus paid


def test_the_unfound_task_study_runs_the_plans_default_row_with_one_change_on_new_seeds():
  """Its runs are the confirmation plan's set #2 default row, the variant's change alone, on
  seeds no set #2 run of the plan holds, and named so that the report tells them apart."""
  from discosyn_jax.experiments import confirm
  from discosyn_jax.experiments.method import Method

  unfound = study("unfound_task")
  plan = confirm.load(ROOT / unfound.PLAN)
  made = list(unfound.configs([8, 9]))
  assert [name for name, _, _ in made] == ["discosyn6-l-reward-zfloor0.7-set2-seed8",
                                           "discosyn6-l-reward-zfloor0.7-set2-seed9"]
  for _, config, meta in made:
    assert config == plan.row("set2-default").run_config(meta["seed"]).replace(z_std_floor=0.7)
    assert Method.parse(meta["method"]) == Method.of(config)
  (name, config, meta), = unfound.configs([8], "task-noise-bonus-cap")
  assert name == "discosyn6-l-reward-tasknoise-bonuscap-set2-seed8"
  assert config == plan.row("set2-default").run_config(8).replace(task_noise=True, bonus_cap=True)
  used = {seed for row in plan.rows if row.name.startswith("set2") for seed in row.seeds}
  assert not used & {meta["seed"] for _, _, meta in unfound.configs([8, 9, 10])}


def test_the_planted_lag_study_reads_a_decoders_reach_along_a_direction():
  """decoder_reach: the most a linear decoder gives along a direction with z at a corner of
  its box, its actions clipped to [-1, 1] as the env clips them."""
  import numpy as np

  lag = study("planted_lag")
  kernel = np.zeros((3, 20))
  kernel[0, 0], kernel[1, 1] = 0.5, 0.25
  direction = np.zeros(20)
  direction[:2] = [0.6, 0.8]
  decoder = {"synergies.kernel": kernel, "synergies.bias": np.zeros(20)}
  assert lag.decoder_reach(decoder, direction) == pytest.approx(0.6 * 0.5 + 0.8 * 0.25)
  decoder["synergies.bias"][0] = 0.8  # 1.3 on the first action, clipped to 1
  assert lag.decoder_reach(decoder, direction) == pytest.approx(0.6 * 1.0 + 0.8 * 0.25)
  assert lag._excursion("planted0") is None and lag._excursion("planted_far3")[1] == 1.4


def test_the_solving_reach_study_measures_the_distance_to_a_decoders_box():
  """distance: the RMS per actuator from each action to {W u + c : u in [-1, 1]^b}, averaged
  over the actions: 0 inside it, the part outside the span or past the box's face else."""
  import numpy as np

  reach = study("solving_reach")
  kernel = np.zeros((2, 20))
  kernel[0, 0], kernel[1, 1] = 0.5, 1.0
  bias = np.zeros(20)
  inside = np.zeros((1, 20))
  inside[0, :2] = [0.25, -1.0]
  assert reach.distance(kernel, bias, inside) == pytest.approx(0.0, abs=1e-9)
  past = np.zeros((1, 20))
  past[0, 0] = 0.9  # 0.4 past the box's face along the first synergy
  off = np.zeros((1, 20))
  off[0, 2] = 0.2  # outside the span
  assert reach.distance(kernel, bias, past) == pytest.approx(np.sqrt(0.4 ** 2 / 20))
  assert reach.distance(kernel, bias, np.concatenate([past, off])) == pytest.approx(
      (np.sqrt(0.4 ** 2 / 20) + np.sqrt(0.2 ** 2 / 20)) / 2)
  assert reach.distance(kernel, bias + 0.1, inside + 0.1) == pytest.approx(0.0, abs=1e-9)


def test_the_transfer_learned_study_learns_on_the_frozen_transfers_run(tmp_path):
  from discosyn_jax.experiments import record

  module = study("transfer_learned")
  source = ROOT / "docs/results/paper/discosyn3-l-reward-set1-seed1"
  frozen = record.saved_config(ROOT / "docs/results/paper/transfer-synergies-set1-seed1")
  tuned = module.row_config("tuned", 1, source)
  # the frozen transfer's run with its decoder learned on, and nothing else of the run moved
  assert tuned.replace(freeze_decoder=True, alpha2=0.0, alpha3=0.0, closing_episodes=0,
                       checkpoint_every=100, decoder_from=frozen.decoder_from) == frozen
  assert tuned.decoder_from == str((source / "decoder.npz").resolve())
  both = module.row_config("tuned-tncap", 1, source)
  assert both == tuned.replace(task_noise=True, bonus_cap=True)
  scratch = module.row_config("scratch", 1, None)
  assert (scratch.decoder_from, scratch.decoder_init, scratch.tasks) == ("", "reward", frozen.tasks)
  with pytest.raises(SystemExit):
    module.main(["--rows", "frozen-from", "--out", str(tmp_path)])  # no --source


def test_the_task_alone_study_trains_the_plans_set2_rows_on_one_task_beside_the_set():
  """Its runs are the plan's set #2 default and PPO rows with the task alone, nothing else
  changed; its table puts each row's runs alone beside its runs inside the set, the env steps
  of the task to 0.8 read the same way for both."""
  from discosyn_jax.experiments import confirm, report_runs
  from discosyn_jax.experiments.method import Method

  alone = study("task_alone")
  plan = confirm.load(alone.PLAN)
  made = list(alone.configs("dice", [0]))
  assert [name for name, _, _ in made] == ["discosyn6-l-reward-dice-seed0", "ppo-dice-seed0"]
  for (_, config, meta), row in zip(made, alone.ROWS):
    assert config == plan.row(row).run_config(0).replace(tasks=("dice",))
    assert (meta["set"], Method.parse(meta["method"])) == ("dice", Method.of(config))
  assert alone._methods() == {"DiscoSyn6-L-reward", "PPO"}

  config = made[0][1]

  def run(seed, successes, task_set):
    evaluations = [{"step": 50 * (i + 1), "dice/success": s} for i, s in enumerate(successes)]
    return report_runs.LabelledRun(path=pathlib.Path("x"), config=config, evaluations=evaluations,
                           metrics=[], experiment="task-alone", method=Method.of(config),
                           task_set=task_set, seed=seed, scale="cpu")

  lines = alone.table([run(0, [0.1, 0.9, 0.8, 0.7], "dice")],
                      [run(11, [0.0, 0.2, 0.4, 0.6], "set2")], "dice")
  per_step = config.num_envs * config.unroll_length
  assert lines[2] == (f"| DiscoSyn6-L-reward | alone | 0 | 0.62 (**0.62**) | 0.80 (**0.80**) | "
                      f"{100 * per_step / 1e6:.2f} (1 of 1) |")
  assert lines[3] == ("| DiscoSyn6-L-reward | in set #2 | 11 | 0.30 (**0.30**) | "
                      "0.40 (**0.40**) | - (0 of 1) |")


def test_the_task_alone_study_learns_on_from_a_set2_decoder_copied_beside_its_runs(tmp_path):
  """--sources: the default row on the task alone, its decoder learned on from the set #2
  run's, the seed the source's; the source's record copied beside so a kept run names it by
  its sibling folder, not by a path of the machine."""
  from discosyn_jax.experiments import confirm

  alone = study("task_alone")
  source = alone.BESIDE[1] / "set2-default-seed11"
  (name, config, meta), = alone.from_set("dice", [source], tmp_path)
  assert name == "discosyn6-l-reward-tuned-dice-seed11"
  assert meta["method"] == "DiscoSyn6-L-reward tuned" and meta["seed"] == 11
  copied = tmp_path / source.name / "decoder.npz"
  assert copied.read_bytes() == (source / "decoder.npz").read_bytes()
  row = confirm.load(alone.PLAN).row("set2-default").run_config(11)
  assert config == row.replace(tasks=("dice",), decoder_init="random",
                               decoder_from=str(copied.resolve()))
  assert not config.freeze_decoder and config.alpha2 == row.alpha2
  with pytest.raises(SystemExit) as stop:
    alone.main(["--seeds", "--sources", str(tmp_path / "nothing"), "--out", str(tmp_path)])
  assert stop.value.code == 2


def test_the_paper_budget_study_reads_success_and_drift_at_each_budget(capsys):
  """At 1x a `cpu` run's budget is its whole run: its final per task is the record's final
  (the mean of its last 3 evaluations), and it is solved first where every task's mean of
  3 is at 0.8."""
  from discosyn_jax.experiments import report_runs

  budget = study("paper_budget")
  run = report_runs.find([ROOT / "docs/results/paper/discosyn3-l-reward-set1-seed0"])[0][0]
  final = budget.final_at(run, budget.cpu_steps("set1"))
  assert final == pytest.approx({t: run.final[f"{t}/success"] for t in run.config.tasks})
  first = budget.first_solved(run)
  at = next(r["step"] for r in run.evaluations if r["env_steps"] == first)
  assert min(budget.final_at(run, at).values()) >= 0.8
  assert all(min(budget.final_at(run, r["step"]).values()) < 0.8
             for r in run.evaluations if r["step"] < at)
  assert 0 < budget.drift_at(run, 300)["decoder/overlap_start"] <= 1
  budget.main([str(run.path)])
  out = capsys.readouterr().out
  assert "| discosyn3-l-reward-set1-seed0 | 1x | 1.54 M |" in out and "2x" not in out
  assert budget.reference_overlap(run, ROOT / "docs/results/paper") == pytest.approx(1.0, abs=1e-5)
  # the reward prior starts every seed in one space: their ends agree, far above chance
  runs = report_runs.find([ROOT / f"docs/results/paper/discosyn3-l-reward-set1-seed{s}"
                           for s in (0, 1)])[0]
  [row] = [line for line in budget.across_seeds(runs).splitlines() if line.startswith("| DiscoSyn3")]
  _, method, seeds, pair, chance, _ = row.split("|")
  assert (method.strip(), seeds.strip(), chance.strip()) == ("DiscoSyn3-L-reward", "0, 1", "0.15")
  assert 0.9 < float(pair) <= 1.0 + 1e-6
