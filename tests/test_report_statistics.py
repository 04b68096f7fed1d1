"""The report's intervals (discosyn_jax/experiments/intervals.py, rliable's bootstrap): known
answers on tiny score matrices, the statistics equal to rliable's own, and the report's
interval tables and profiles for the committed fixture, the same on every run."""

import shutil

import numpy as np
import pytest

from discosyn_jax.experiments import intervals, report
from discosyn_jax.experiments.method import Method
from tests.report_fixture import FIXTURE

REPS = 500  # enough for the orderings asserted here, and quick


def test_identical_scores_give_an_even_chance_and_a_sweep_gives_one():
  x = np.array([[0.2, 0.9], [0.5, 0.7], [0.8, 1.0]])
  even = intervals.probability_of_improvement({"s": x}, {"s": x.copy()}, reps=REPS)["s"]
  assert even.value == 0.5 and even.low <= 0.5 <= even.high
  assert intervals.verdict(even) == "not separated"
  assert intervals.seeds_to_separate(even, 3) is None  # no gap to separate

  better = intervals.probability_of_improvement({"s": x + 1.5}, {"s": x}, reps=REPS)["s"]
  assert (better.value, better.low, better.high) == (1.0, 1.0, 1.0)
  assert intervals.verdict(better) == "above"
  worse = intervals.probability_of_improvement({"s": x}, {"s": x + 1.5}, reps=REPS)["s"]
  assert (worse.value, worse.high) == (0.0, 0.0) and intervals.verdict(worse) == "below"


def test_the_iqm_and_the_mean_of_known_numbers():
  scores = np.arange(1.0, 9.0).reshape(4, 2)  # 1..8: the middle half is 3, 4, 5, 6
  assert intervals.iqm(scores) == 4.5
  iqm, mean = intervals.aggregates({"s": scores}, reps=REPS)["s"]
  assert iqm.value == 4.5 and mean.value == 4.5
  assert iqm.low <= 4.5 <= iqm.high and mean.low < 4.5 < mean.high
  outlier = np.array([[0.0, 0.5], [0.5, 0.5], [0.5, 0.5], [0.5, 100.0]])
  assert intervals.iqm(outlier) == 0.5  # a quarter cut from each end


def test_the_statistics_are_rliables_own():
  from rliable import library, metrics

  rng = np.random.default_rng(0)
  levels = np.linspace(0, 1, 11)
  for runs_x, runs_y, tasks in ((3, 3, 4), (5, 3, 2), (2, 7, 1)):
    # scores on a grid of 1/8, as success over few episodes is: ties are common
    x = rng.integers(0, 9, (runs_x, tasks)) / 8
    y = rng.integers(0, 9, (runs_y, tasks)) / 8
    assert intervals.improvement(x, y) == pytest.approx(metrics.probability_of_improvement(x, y))
    assert intervals.iqm(x) == pytest.approx(metrics.aggregate_iqm(x))
    assert intervals.mean(x) == pytest.approx(metrics.aggregate_mean(x))
    np.testing.assert_allclose(intervals.score_distribution(x, levels),
                               library.score_distributions(x, levels))


def test_the_interval_narrows_with_more_runs():
  rng = np.random.default_rng(1)
  few, many = rng.uniform(0, 1, (3, 4)), rng.uniform(0, 1, (30, 4))
  width = lambda e: e.high - e.low
  (iqm_few, mean_few), = intervals.aggregates({"s": few}, reps=REPS).values()
  (iqm_many, mean_many), = intervals.aggregates({"s": many}, reps=REPS).values()
  assert width(mean_many) < width(mean_few) / 2 and width(iqm_many) < width(iqm_few)
  profile, low, high = intervals.performance_profile({"s": many}, [0.5], reps=REPS)["s"]
  assert low[0] <= profile[0] <= high[0]


def test_the_bootstrap_is_the_same_every_time_and_leaves_numpys_random_state_alone():
  x, y = np.array([[0.1, 0.4], [0.9, 0.3], [0.6, 0.8]]), np.array([[0.2, 0.5], [0.4, 0.1]])
  np.random.seed(123)
  before = np.random.get_state()[1].copy()
  first = intervals.probability_of_improvement({"a": x, "b": 1 - x}, {"a": y, "b": 1 - y}, REPS)
  assert np.array_equal(np.random.get_state()[1], before)
  # whatever ran before: the same numbers
  np.random.seed(7)
  again = intervals.probability_of_improvement({"a": x, "b": 1 - x}, {"a": y, "b": 1 - y}, REPS)
  assert first == again
  # two scores bootstrapped together: each its own point estimate
  alone = intervals.probability_of_improvement({"a": x}, {"a": y}, REPS)["a"]
  assert first["a"].value == alone.value


def test_the_seeds_that_would_separate_a_gap():
  # P = 0.7, 0.3 below it at 3 seeds: the half-width 0.3 shrinks below the gap 0.2 from
  # 3 * (0.3 / 0.2)^2 = 6.75 seeds, so 7
  p = intervals.Estimate(0.7, 0.4, 0.9)
  assert intervals.verdict(p) == "not separated"
  assert intervals.seeds_to_separate(p, 3) == 7
  assert intervals.seeds_to_separate(intervals.Estimate(0.3, 0.1, 0.6), 3) == 7  # mirrored
  assert intervals.verdict(intervals.Estimate(0.7, 0.55, 0.9)) == "above"


def test_the_default_row_of_each_set():
  default = lambda task_set, rows: report.default_method(task_set, list(map(Method.parse, rows)))
  rows = ["PPO", "Random6-L-zfree", "DiscoSyn4-L-reward", "DiscoSyn6-L-reward"]
  assert default("set2", rows).name == "DiscoSyn6-L-reward"
  assert default("set1", ["PPO", "DiscoSyn3-L", "Random3-L-zfree"]).name == "DiscoSyn3-L"
  assert default("unseen-set1", ["PPO", "DiscoSyn3-L-reward frozen"]).name == \
      "DiscoSyn3-L-reward frozen"
  assert default("Press+Rake", ["Random3-L", "DiscoSyn3-L-reward"]).name == "DiscoSyn3-L-reward"
  assert default("set1", ["PPO", "PCA4"]) is None


def test_the_row_with_a_residual_is_measured_against_the_others():
  from types import SimpleNamespace as ns

  res, control = Method.parse("DiscoSyn3-L-reward-res0.3r150"), Method.parse("Random3-L-zfree-res0.3r150")
  rows = {Method.parse("DiscoSyn3-L-reward"): 0.0, res: 0.3, control: 0.3, Method("PPO"): 0.0}
  runs = [ns(method=m, config=ns(residual=rho)) for m, rho in rows.items()]
  assert report.residual_methods(runs, rows) == [res]
  assert report.residual_methods([r for r in runs if r.method != res], rows) == []

  x = np.array([[0.5, 1.0], [0.75, 1.0], [1.0, 0.75]])
  matrices = {kind: {res: x, control: x.copy(), Method("PPO"): x * 0} for kind in report.SCORES}
  table = report.improvement_table(matrices, res)
  lines = table.splitlines()
  assert lines[0] == (f"| method | runs | P({res} > row), final success | "
                      f"P({res} > row), mean over the curve |")
  assert len(lines) == 4 and not any(line.startswith(f"| {res} |") for line in lines)
  cells = lines[2].split(" | ")
  assert cells[:2] == [f"| {control}", "3"] and len(cells) == 4
  assert all(c.startswith("0.50 [") and "] not separated at 3 (no gap)" in c for c in cells[2:])
  assert lines[3] == "| PPO | 3 | " + " | ".join(["1.00 [1.00, 1.00] above"] * 2) + " |"


def test_the_report_gives_every_set_its_intervals_and_profile_the_same_every_time(tmp_path):
  folder = tmp_path / "report-ci"
  shutil.copytree(FIXTURE, folder)
  out = folder / "report"
  made = []
  for _ in range(2):
    text = report.write([folder], out, with_tsne=False, force=True).read_text()
    made.append((text, {p.name: p.read_bytes() for p in sorted(out.glob("profile-*.png"))}))
  assert made[0] == made[1]
  text, figures = made[0]
  for task_set in ("set1", "set2", "sparse", "unseen-set1", "unseen-set2"):
    assert f"### {task_set}: intervals over runs x tasks" in text
    assert f"profile-{task_set}.png" in figures and f"](profile-{task_set}.png)" in text
  assert "P(DiscoSyn3-L > row), final success" in text
  assert f"rliable, {intervals.REPS:,} replications, seed {intervals.SEED}" in text
