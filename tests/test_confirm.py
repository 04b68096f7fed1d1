"""A final that one evaluation cannot swing (the mean of the last k evaluations, the closing
evaluation), confirmation plans (experiments/confirm.py) and the residual's schedule as a
share of the run."""

import json
import pathlib

import numpy as np
import pytest

from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.experiments import confirm, intervals, paper, presets, report, report_runs
from discosyn_jax.experiments.method import Method
from discosyn_jax.run import folder, layout
from discosyn_jax.training import loop
from discosyn_jax.training.trainer import Trainer
from tests import helpers
from tests.helpers import ROOT
from tests.toy_env import ReachAction

TOY = TrainConfig(tasks=("a", "b"), n_synergies=2, policy_hidden=(16, 16), value_hidden=(16, 16),
                  discriminator_hidden=(16, 16), num_envs=8, unroll_length=4, num_minibatches=2,
                  update_epochs=1, eval_envs=4, eval_every=1, steps=3, checkpoint_every=0,
                  closing_episodes=16, decoder_init="random")


def toy_trainer(config):
  return Trainer(config, envs=[ReachAction(0.5), ReachAction(-0.5, obs_size=5)])


def fake_run(folder, config, successes, closing=None, meta=None):
  """A run folder as a record holds it: config.json, eval.jsonl with these successes (one
  row per evaluation: {task: success}), closing.json where given, experiment.json."""
  folder.mkdir(parents=True)
  config_lib.save(config, folder / layout.CONFIG_FILE)
  rows = [{"step": (i + 1) * config.steps // len(successes), "env_steps": 0,
           **{f"{t}/success": s for t, s in row.items()}} for i, row in enumerate(successes)]
  (folder / layout.EVAL_FILE).write_text("".join(json.dumps(r) + "\n" for r in rows))
  if closing is not None:
    (folder / layout.CLOSING_FILE).write_text(json.dumps(
        {"step": config.steps, **{f"{t}/success": s for t, s in closing.items()}}))
  if meta is not None:
    (folder / layout.EXPERIMENT_FILE).write_text(json.dumps(meta))
  return folder


# -- the final: the mean of the last k evaluations; the closing evaluation -------------------
def test_the_final_is_the_mean_of_the_last_k_evaluations(tmp_path):
  evals = [{"step": s, "a/success": v, "a/return": 10 * v} for s, v in ((1, 0.0), (2, 0.5), (3, 0.25), (4, 1.0))]
  at_end = lambda rows, k: folder.Run(tmp_path, TOY, rows, []).at_end(k)
  assert at_end(evals, 1) == evals[-1]
  three = at_end(evals, 3)
  assert three["a/success"] == pytest.approx((0.5 + 0.25 + 1.0) / 3)
  assert three["a/return"] == pytest.approx(10 * (0.5 + 0.25 + 1.0) / 3)
  assert three["step"] == 4  # the newest row's own step
  assert at_end(evals[:2], 3)["a/success"] == 0.25  # a run with fewer: all it has
  assert at_end([], 3) == {}
  # through the report: the solved table's cell and the run's final, k from the flag
  config = TOY.replace(steps=4).validate()
  fake_run(tmp_path / "runs" / "r", config, [{"a": v, "b": 1.0} for v in (0.0, 0.5, 0.25, 1.0)])
  (run,), _ = report_runs.find([tmp_path / "runs"], final_k=3)
  assert run.final["a/success"] == pytest.approx(1.75 / 3)
  for k, cell in ((1, "✓ 100%"), (3, "✗ 58%")):
    text = report.write([tmp_path / "runs"], tmp_path / f"report{k}", with_tsne=False,
                        final_k=k).read_text()
    assert f"| {cell} [1] | ✓ 100% [1] |" in text, text
    assert f"mean of its last {k} deterministic" in text
  with pytest.raises(ValueError, match="at least 1 evaluation"):
    report_runs.find([tmp_path / "runs"], final_k=0)


def test_every_run_ends_with_a_closing_evaluation_kept_in_its_record(tmp_path):
  done = loop.train(toy_trainer(TOY), tmp_path / "run", progress=False, log=lambda *_: None)
  closing = json.loads((tmp_path / "run" / layout.CLOSING_FILE).read_text())
  assert closing["step"] == 3 and closing["episodes"] == 16
  assert set(closing) >= {"a/success", "a/return", "b/success", "b/return"}
  assert closing["a/return"] == pytest.approx(done["closing"]["a"]["return"])
  # its own episodes: not the last evaluation of the curve, whose 4 episodes are a subset
  last = json.loads((tmp_path / "run" / layout.EVAL_FILE).read_text().splitlines()[-1])
  assert closing["a/return"] != last["a/return"]
  from discosyn_jax.experiments import record

  assert layout.CLOSING_FILE in record.files(TOY)
  assert layout.CLOSING_FILE not in record.files(TOY.replace(closing_episodes=0))
  (run,), _ = report_runs.find([tmp_path / "run"])
  assert run.closing["b/success"] == closing["b/success"]
  none = loop.train(toy_trainer(TOY.replace(closing_episodes=0)), tmp_path / "none",
                    progress=False, log=lambda *_: None)
  assert none["closing"] is None and not (tmp_path / "none" / layout.CLOSING_FILE).exists()


def test_a_finished_run_without_a_closing_evaluation_is_still_the_planned_run(tmp_path):
  """Records made before the closing evaluation (closing_episodes 0) are finished runs of
  today's config: an experiment keeps them rather than training them again."""
  config = TOY.replace(closing_episodes=0)
  fake_run(tmp_path / "old", config, [{"a": 1.0, "b": 1.0}] * 3)
  for name in ("metrics.jsonl.xz", "decoder.npz", "z.npz", "experiment.json"):
    (tmp_path / "old" / name).write_text("")
  from discosyn_jax.experiments import record

  assert record.finished(tmp_path / "old", TOY)
  assert not record.finished(tmp_path / "old", TOY.replace(alpha1=0.5))
  assert config_lib.same_run(TOY, config) and not config_lib.same_run(TOY, TOY.replace(seed=1))


# -- plans --------------------------------------------------------------------------------
def tiny_plan(**changes):
  base = presets.preset("planted-disco3-linear").replace(
      **{**paper.SCALES["ci"].train, "steps": 2, "closing_episodes": 4})
  late = base.replace(residual=0.3, residual_start=0.5, residual_ramp=0.5)
  plan = {"name": "tiny", "claim": "the late schedule is not below the default", "final_k": 3,
          "level_margin": 0.1,
          "rows": [{"name": "late", "seeds": [0], "config": confirm.row_fields(late)},
                   {"name": "default", "seeds": [0], "config": confirm.row_fields(base)}],
          "hypotheses": [{"x": "late", "y": "default", "score": "final", "expect": "not below"}],
          "decision": "nothing follows."}
  plan.update(changes)
  return plan


def test_a_plan_written_before_a_field_was_added_runs_with_its_value_of_then(tmp_path):
  """A committed plan is never rewritten: a field added since (config.ADDED) takes the value
  every run had before it, as `discosyn upgrade` gives an older run's config."""
  plan = tiny_plan()
  for row in plan["rows"]:
    del row["config"]["z_std_floor"]
  (tmp_path / "plan.json").write_text(json.dumps(plan))
  loaded = confirm.load(tmp_path / "plan.json")
  assert [row.config.z_std_floor for row in loaded.rows] == [config_lib.ADDED["z_std_floor"]] * 2
  assert [row.config for row in loaded.rows] == [row.config for row in confirm.parse(tiny_plan()).rows]
  committed = confirm.load(pathlib.Path(ROOT) / "docs/results/confirm-late-residual/plan.json")
  assert len(committed.rows) == 9 and all(r.config.z_std_floor == 0.0 for r in committed.rows)


def test_a_plan_runs_exactly_its_rows_and_refuses_a_run_that_differs(tmp_path, capsys):
  (tmp_path / "plan.json").write_text(json.dumps(tiny_plan()))
  folders = confirm.run(tmp_path / "plan.json", tmp_path / "out", log=lambda *_: None)
  assert [f.name for f in folders] == ["late-seed0", "default-seed0"]
  late = config_lib.load(tmp_path / "out" / "late-seed0" / "config.json")
  assert (late.seed, late.residual_start_step, late.residual_ramp_step_count) == (0, 1, 1)
  meta = json.loads((tmp_path / "out" / "late-seed0" / "experiment.json").read_text())
  assert meta["experiment"] == "confirm-tiny" and meta["row"] == "late"
  assert meta["method"] == "DiscoSyn3-L-res0.3r1s1"
  assert (tmp_path / "out" / "late-seed0" / layout.CLOSING_FILE).is_file()
  text = report.write([tmp_path / "out"], tmp_path / "report", with_tsne=False).read_text()
  assert "## Confirmation: tiny" in text and "| late vs default (final) | 1, 1 |" in text
  # a run in the folder whose config is not the plan's: one line, exit 2, nothing touched
  changed = tiny_plan()
  changed["rows"][0]["config"]["alpha1"] = 0.5
  (tmp_path / "changed.json").write_text(json.dumps(changed))
  (tmp_path / "out" / confirm.PLAN_FILE).write_text(json.dumps(changed))  # the same plan text
  before = sorted(p.name for p in (tmp_path / "out").iterdir())
  assert cli.main(["experiment", "confirm", str(tmp_path / "changed.json"), "--out",
                   str(tmp_path / "out")]) == 2
  (line,) = [l for l in capsys.readouterr().err.splitlines() if l]
  assert line.endswith("late-seed0 is not the plan's run: its alpha1 is 0.001, the plan's 0.5")
  assert sorted(p.name for p in (tmp_path / "out").iterdir()) == before
  # a folder of another plan
  (tmp_path / "out" / confirm.PLAN_FILE).write_text(json.dumps(tiny_plan()))
  assert cli.main(["experiment", "confirm", str(tmp_path / "changed.json"), "--out",
                   str(tmp_path / "out")]) == 2
  assert "holds the runs of another plan" in capsys.readouterr().err


@pytest.mark.parametrize("change, message", [
    (dict(final_k=0), "final_k must be a whole number >= 1"),
    (dict(level_margin=0.7), "level_margin must be in"),
    (dict(hypotheses=[{"x": "late", "y": "nobody", "score": "final", "expect": "above"}]),
     "no row 'nobody'"),
    (dict(hypotheses=[{"x": "late", "y": "default", "score": "best", "expect": "above"}]),
     "score is one of final, curve, closing"),
    (dict(hypotheses=[{"x": "late", "y": "default", "score": "final", "expect": "better"}]),
     "expect is one of"),
    (dict(extra=1), "unknown field"),
    (dict(decision="missing"), "no 'decision'"),
    (dict(rows={"late": {}}), "rows must be a non-empty list, not"),
    (dict(rows=["late"]), r"rows\[0\] must be an object"),
    (dict(hypotheses=[]), "hypotheses must be a non-empty list"),
    (dict(hypotheses=["late > default"]), r"hypotheses\[0\] must be an object"),
    (dict(hypotheses=[{"x": "late", "y": "late", "score": "final", "expect": "above"}]),
     "compares a row with itself"),
    (dict(hypotheses=[{"x": "late", "y": 3, "score": "final", "expect": "above"}]),
     r"hypotheses\[0\]: y must be a string"),
    (dict(hypotheses=[{"x": "late", "score": "final", "expect": "above"}]), r"hypotheses\[0\]: no y"),
])
def test_a_bad_plan_is_refused_in_one_line_naming_the_file(change, message, tmp_path):
  plan = tiny_plan(**change)
  if plan["decision"] == "missing":
    del plan["decision"]
  (tmp_path / "plan.json").write_text(json.dumps(plan))
  with pytest.raises(ValueError, match=message) as err:
    confirm.load(tmp_path / "plan.json")
  assert str(err.value).startswith(f"plan {tmp_path / 'plan.json'}: ")
  for field, value, line in (("seeds", 3, "row late: seeds must be a list of distinct whole numbers, not 3"),
                             ("seeds", [0, True], "seeds must be a list of distinct whole numbers"),
                             ("seeds", [0, -1], "row late: seed must be a whole number"),
                             ("config", None, "row late: config must be an object of TrainConfig fields, not null"),
                             ("name", "a\x00b", r"rows\[0\]: a row's name is a folder's name"),
                             ("name", "x" * 101, "at most 100 characters")):
    bad = tiny_plan()
    bad["rows"][0][field] = value
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(ValueError, match=line):
      confirm.load(tmp_path / "bad.json")
  seeded = tiny_plan()
  seeded["rows"][0]["config"]["seed"] = 3
  (tmp_path / "seeded.json").write_text(json.dumps(seeded))
  with pytest.raises(ValueError, match="row late: its config gives no seed"):
    confirm.load(tmp_path / "seeded.json")


def test_a_refused_plan_leaves_nothing_and_the_corrected_one_then_runs(tmp_path, capsys):
  plan, out = tiny_plan(), tmp_path / "out"
  tasks_ = plan["rows"][0]["config"]["tasks"]
  for change, line in ((("tasks", [*tasks_, "no_such_task"]), "row late: unknown task or task set 'no_such_task'"),
                       (("hand", "nohand"), "row late: a hand is one of"),
                       (("decoder_from", "missing.npz"), "row late: decoder_from missing.npz does not exist")):
    bad = json.loads(json.dumps(plan))
    bad["rows"][0]["config"][change[0]] = change[1]
    if change[0] == "decoder_from":
      bad["rows"][0]["config"].update(decoder_init="random", freeze_decoder=True, alpha2=0.0, alpha3=0.0)
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    assert cli.main(["experiment", "confirm", str(tmp_path / "bad.json"), "--out", str(out)]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if l]
    assert len(err) == 1 and line in err[0], err
    assert not out.exists()
  # a plan.json that is a folder is named, and nothing is left beside it
  (out / confirm.PLAN_FILE).mkdir(parents=True)
  (tmp_path / "plan.json").write_text(json.dumps(plan))
  assert cli.main(["experiment", "confirm", str(tmp_path / "plan.json"), "--out", str(out)]) == 2
  assert "is not a file" in capsys.readouterr().err
  assert sorted(p.name for p in out.iterdir()) == [confirm.PLAN_FILE]
  # another plan's file that is not UTF-8: named as another plan, not as a decoding error
  (out / confirm.PLAN_FILE).rmdir()
  (out / confirm.PLAN_FILE).write_bytes(b"\xff\xfe{")
  with pytest.raises(ValueError, match="holds the runs of another plan"):
    confirm.check_folder(confirm.load(tmp_path / "plan.json"), out)


def test_two_rows_apart_in_a_field_the_name_does_not_carry_are_told_apart(tmp_path):
  base = TOY.replace(tasks=("valve0", "valve1"))
  plan = confirm.parse(tiny_plan(
      rows=[{"name": "slow", "seeds": [0], "config": confirm.row_fields(base)},
            {"name": "fast", "seeds": [0], "config": confirm.row_fields(base.replace(learning_rate=1e-3))}],
      hypotheses=[{"x": "fast", "y": "slow", "score": "final", "expect": "not below"}]))
  methods = [s.meta["method"] for s in confirm.steps(plan, tmp_path)]
  assert methods == ["DiscoSyn2-L-slow", "DiscoSyn2-L-fast"]
  for name in methods:
    assert Method.parse(name).name == name


def planted_runs(tmp_path, x_scores, y_scores):
  """report_runs.LabelledRun objects of rows x and y, seed by seed: each a list of {task: success}
  per evaluation."""
  runs = []
  for row, per_seed in (("late", x_scores), ("default", y_scores)):
    for seed, evals in enumerate(per_seed):
      rows = [{"step": i + 1, **{f"{t}/success": v for t, v in e.items()}} for i, e in enumerate(evals)]
      runs.append(report_runs.LabelledRun(path=tmp_path / f"{row}-seed{seed}", config=TrainConfig(),
                                  experiment="confirm-tiny", method=row, task_set="s", seed=seed,
                                  evaluations=rows, metrics=[], finished=True, scale=None,
                                  closing={f"{t}/success": v for t, v in evals[-1].items()}))
  return runs


@pytest.mark.parametrize("x, y, verdict, holds", [
    (0.9, 0.1, "above", {"above": True, "not below": True, "level": False, "below": False}),
    (0.1, 0.9, "below", {"above": False, "not below": False, "not above": True}),
    (0.5, 0.5, "level", {"level": True, "not below": True, "above": False}),
])
def test_a_verdict_on_planted_numbers_has_the_known_answer(x, y, verdict, holds, tmp_path):
  tasks_ = [f"valve{i}" for i in range(4)]
  seeds = range(5)
  make = lambda v: [[{t: v for t in tasks_}] * 3 for _ in seeds]
  plan = confirm.parse(tiny_plan(rows=[
      {"name": name, "seeds": list(seeds), "config": confirm.row_fields(TrainConfig(tasks=tuple(tasks_)))}
      for name in ("late", "default")]))
  runs = planted_runs(tmp_path, make(x), make(y))
  for score in confirm.SCORES:
    for expect, expected in holds.items():
      plan_h = confirm.Plan(**{**plan.__dict__, "hypotheses": (
          confirm.Hypothesis("late", "default", score, expect),)})
      (found,) = confirm.verdicts(plan_h, runs)
      assert found.verdict == verdict and found.holds is expected, (score, expect)
      assert found.runs == (5, 5)
      assert found.p.value == pytest.approx({"above": 1.0, "below": 0.0, "level": 0.5}[verdict])
  # a row one seed short: the verdict is shown, whether it holds is pending
  (found,) = confirm.verdicts(plan, runs[:-1])
  assert found.holds is None and found.runs == (5, 4)
  # one run a row: no verdict from a bootstrap of one
  (found,) = confirm.verdicts(plan, [runs[0], runs[5]])
  assert found.verdict == "too few runs" and found.holds is None and found.runs == (1, 1)


@pytest.mark.parametrize("damaged", [float("nan"), 7.5, -0.1, "0.5"])
def test_a_damaged_success_is_refused_naming_the_run_and_the_evaluation(damaged, tmp_path):
  tasks_ = ["valve0", "valve1"]
  make = lambda v: [[{t: v for t in tasks_}] * 3 for _ in range(3)]
  plan = confirm.parse(tiny_plan(rows=[
      {"name": name, "seeds": [0, 1, 2], "config": confirm.row_fields(TrainConfig(tasks=tuple(tasks_)))}
      for name in ("late", "default")]))
  runs = planted_runs(tmp_path, make(0.5), make(0.5))
  runs[1].evaluations[1]["valve1/success"] = damaged
  with pytest.raises(ValueError, match=r"late-seed1: valve1/success is .* in the evaluation at "
                                       r"step 2, not a success in \[0, 1\]"):
    confirm.verdicts(plan, runs)


def test_interleaved_rows_are_not_separated():
  """Two rows whose seeds interleave (0.2, 0.4, ... against 0.3, 0.5, ...) on one task:
  P = 11 / 25 with an interval that spans 0.5 widely: neither above nor level."""
  from discosyn_jax.experiments import intervals

  x = np.array([[0.2], [0.4], [0.6], [0.8], [1.0]])
  y = np.array([[0.3], [0.5], [0.7], [0.9], [0.95]])
  p = intervals.probability_of_improvement({"final": x}, {"final": y})["final"]
  assert p.value == pytest.approx(0.44)
  assert confirm.judge(p, 0.1) == "not separated"
  assert confirm.judge(intervals.Estimate(0.5, 0.45, 0.58), 0.1) == "level"
  assert confirm.judge(intervals.Estimate(0.5, 0.35, 0.58), 0.1) == "not separated"


def test_the_mean_difference_on_planted_numbers_has_the_known_answer(tmp_path):
  """x 0.8 and y 0.7 on every run of valve0 and both 1.0 on valve1-3: P over the four tasks
  is diluted to 0.625 by the ties; the difference over them is 0.025 exactly and above 0;
  restricted to valve0, P = 1 and the difference 0.1."""
  tasks_ = [f"valve{i}" for i in range(4)]
  make = lambda v: [[{"valve0": v, **{t: 1.0 for t in tasks_[1:]}}] * 3 for _ in range(5)]
  rows = [{"name": name, "seeds": list(range(5)),
           "config": confirm.row_fields(TrainConfig(tasks=tuple(tasks_)))} for name in ("late", "default")]
  runs = planted_runs(tmp_path, make(0.8), make(0.7))
  h = lambda **kw: {"x": "late", "y": "default", "score": "curve", "expect": "above", **kw}
  plan = confirm.parse(tiny_plan(rows=rows, hypotheses=[
      h(), h(statistic="difference"), h(statistic="difference", task="valve0"),
      h(task="valve0"), h(statistic="difference", expect="level")]))
  found = confirm.verdicts(plan, runs)
  assert found[0].p.value == pytest.approx(0.625)
  assert (found[1].p.value, found[1].p.low, found[1].p.high) == pytest.approx((0.025,) * 3)
  assert found[1].verdict == "above" and found[1].holds
  assert found[2].p.value == pytest.approx(0.1) and found[2].verdict == "above"
  assert found[3].p.value == pytest.approx(1.0)
  assert found[4].holds is False  # above, not level
  # level: a difference inside 0 +- level_margin / 2
  assert confirm.judge(intervals.Estimate(0.01, -0.03, 0.04), 0.1, "difference") == "level"
  assert confirm.judge(intervals.Estimate(0.01, -0.06, 0.04), 0.1, "difference") == "not separated"
  assert confirm.judge(intervals.Estimate(-0.1, -0.16, -0.04), 0.1, "difference") == "below"
  lines = "\n".join(confirm.report_lines(plan, runs))
  assert "late vs default (valve0, curve, difference) | 5, 5 | +0.100 [+0.100, +0.100] | above" in lines
  with pytest.raises(ValueError, match="task 'dice' is not one both rows train"):
    confirm.parse(tiny_plan(rows=rows, hypotheses=[h(task="dice")]))
  with pytest.raises(ValueError, match="statistic is one of P, difference"):
    confirm.parse(tiny_plan(rows=rows, hypotheses=[h(statistic="median")]))


def test_the_seeds_a_plan_needs_come_from_the_spread_and_the_effect():
  # sd 0.05 each, an effect of 0.05, as many runs each: sqrt(n / 2) >= 1.96 + 0.84 -> n = 16
  assert intervals.seeds_for(0.05, 0.05, 0.05) == 16
  # 13 runs of y already there: the least n that clears it
  n = intervals.seeds_for(0.05, 0.05, 0.06, runs_y=13)
  se = lambda n: (0.05 ** 2 / n + 0.05 ** 2 / 13) ** 0.5
  assert 0.06 / se(n) >= 2.8016 > 0.06 / se(n - 1)
  with pytest.raises(ValueError, match="no run count"):
    intervals.seeds_for(0.05, 0.05, 0.01, runs_y=2)


def test_a_row_of_committed_records_is_read_not_run_and_its_configs_checked(tmp_path, capsys):
  plan_dir, records = tmp_path / "plans" / "mine", tmp_path / "older"
  base = TrainConfig(tasks=("valve0", "valve1"), steps=3)
  for seed in (0, 1):
    fake_run(records / f"ppo-seed{seed}", base.replace(seed=seed), [{"valve0": 0.5, "valve1": 0.5}] * 3)
  plan = tiny_plan(rows=[
      {"name": "new", "seeds": [5], "config": confirm.row_fields(base.replace(n_synergies=4))},
      {"name": "old", "seeds": [0, 1], "config": confirm.row_fields(base),
       "records": ["../../older/ppo-seed0", "../../older/ppo-seed1"]}],
      hypotheses=[{"x": "new", "y": "old", "score": "final", "expect": "not below"}])
  plan_dir.mkdir(parents=True)
  (plan_dir / "plan.json").write_text(json.dumps(plan))
  loaded = confirm.load(plan_dir / "plan.json")
  assert [s.name for s in confirm.steps(loaded, tmp_path / "out")] == ["new-seed5"]
  assert [p.resolve() for p in confirm.record_paths(loaded)] == [
      (records / f"ppo-seed{s}").resolve() for s in (0, 1)]
  runs = [report_runs.read(p) for p in confirm.record_paths(loaded)]
  (found,) = confirm.verdicts(loaded, runs)
  assert found.runs == (0, 2)
  # a record that is not the row's run, or that is missing, refuses the plan by name
  fake_run(records / "other-seed1", base.replace(seed=1, learning_rate=1e-3), [{"valve0": 0.5}] * 3)
  for wrong, message in (("../../older/other-seed1", "its learning_rate is 0.001, the row's 0.0003"),
                         ("../../older/none", "no record of seed 1")):
    plan["rows"][1]["records"][1] = wrong
    (plan_dir / "plan.json").write_text(json.dumps(plan))
    with pytest.raises(ValueError, match=message):
      confirm.load(plan_dir / "plan.json")
  with pytest.raises(ValueError, match="records must be one folder per seed"):
    confirm.parse({**plan, "rows": [{**plan["rows"][1], "records": ["a"]}]})


# -- the residual's schedule, a share of the run ----------------------------------------------
def test_the_schedule_is_a_share_of_the_run_and_means_the_same_at_every_scale(tmp_path):
  late = presets.preset("set2-disco6-linear-residual-late")
  for steps, start, ramp in ((1200, 400, 200), (300, 100, 50), (600, 200, 100)):
    config = late.replace(steps=steps)
    assert (config.residual_start_step, config.residual_ramp_step_count) == (start, ramp)
    assert Method.of(config).name == f"DiscoSyn6-L-reward-res0.3r{ramp}s{start}"
  # a config of an older release, its schedule in train steps, loads as the same shares
  old = late.replace(steps=1200).to_dict()
  del old["residual_start"], old["residual_ramp"], old["closing_episodes"]
  old.update(residual_start_steps=400, residual_ramp_steps=200)
  (tmp_path / "config.json").write_text(json.dumps(old))
  with pytest.raises(ValueError, match="discosyn upgrade .* closing_episodes = 0"):
    config_lib.load(tmp_path / "config.json")
  assert config_lib.upgrade(tmp_path / "config.json") == [
      "closing_episodes", "residual_ramp (was residual_ramp_steps)",
      "residual_start (was residual_start_steps)"]
  upgraded = config_lib.load(tmp_path / "config.json")
  assert upgraded == late.replace(steps=1200, closing_episodes=0)
  # the schedule is a share of steps: a scheduled run continued with other steps is refused
  assert any("share of steps" in m for m in config_lib.mismatches(upgraded, upgraded.replace(steps=2400)))
  plain = presets.preset("set2-disco6-linear")
  assert config_lib.mismatches(plain, plain.replace(steps=2400)) == []


def test_a_plan_damaged_at_random_is_read_or_refused_in_one_line(tmp_path):
  """Bits flipped and cuts at random points of a committed plan: each either reads as a plan
  (a flip in its prose, or a digit that still makes one) that is runnable or refused as such,
  or is refused in one line naming the file; never another exception."""
  import random

  good = (pathlib.Path(ROOT) / "docs/results/confirm-own-synergies-transfer/plan.json").read_bytes()
  rng = random.Random(0)
  outcomes = {"read": 0, "refused": 0}
  for trial in range(60):
    path = tmp_path / f"t{trial}" / confirm.PLAN_FILE
    path.parent.mkdir()
    path.write_bytes(helpers.damaged(good, trial, rng))
    try:
      plan = confirm.load(path)
    except confirm.PlanError as err:
      assert "\n" not in str(err) and str(path) in str(err), err
      outcomes["refused"] += 1
      continue
    try:
      confirm.check_runnable(plan)
    except confirm.PlanError as err:  # a plan of a task or hand that is not there: its field named
      assert "\n" not in str(err), err
    outcomes["read"] += 1
  assert outcomes["refused"] >= 30 and outcomes["read"] > 0  # every cut short is refused
