"""Aggregates a reviewer can trust from a few seeds (Agarwal et al., "Deep RL at the Edge of
the Statistical Precipice", NeurIPS 2021), through their library `rliable`: the
interquartile mean (IQM) and the mean of a runs x tasks score matrix, the probability that
one method improves on another, and the performance profile, each with its 95 % stratified
bootstrap interval (runs resampled within each task).

Arrays in, numbers out: this module knows nothing of runs or files (report.py reads those).
Each function takes several scores of the same runs and tasks (the final success, the mean
over the curve: {name: runs x tasks matrix}) and bootstraps them in one pass of rliable's
StratifiedBootstrap over a runs x tasks x scores array, which resamples the runs within
each task and score: each score's interval is that of its own stratified bootstrap.

Every bootstrap starts from the same seed, so that the same scores give the same intervals
byte for byte, whichever other rows a report holds. rliable draws its indices from NumPy's
global random state, not from the `random_state` it is given: `_seeded` sets that state for
the call and puts it back.

The IQM, the probability of improvement and the profile are evaluated thousands of times
per row, so each is written here in a few NumPy operations, equal to rliable's own
(`metrics.aggregate_iqm`: scipy's trim_mean; `metrics.probability_of_improvement`: a
Mann-Whitney U per task; `library.score_distributions`), which
tests/test_report_statistics.py checks; rliable's took minutes for a report on 2 cores. The
bootstrap itself is rliable's.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np

from discosyn_jax.checks import BadInput

# 2,000 replications for every interval: rliable's own for profiles and its README's for the
# probability of improvement; with 3-5 seeds a task the bootstrap distribution has few
# distinct values, and its default 50,000 for aggregates would be most of a report's time
REPS = 2000
SEED = 0
CONFIDENCE = 0.95


@dataclasses.dataclass(frozen=True)
class Estimate:
  """A point estimate and its confidence interval."""
  value: float
  low: float
  high: float


# -- the statistics, on a runs x tasks (x scores) array -----------------------------
def iqm(scores: np.ndarray) -> np.ndarray:
  """The interquartile mean of all runs x tasks scores, per score: the mean of the middle
  half, a quarter cut from each end (rliable's `metrics.aggregate_iqm`)."""
  flat = np.sort(scores.reshape(-1, *scores.shape[2:]), axis=0)
  cut = int(0.25 * len(flat))
  return flat[cut:len(flat) - cut].mean(axis=0)


def mean(scores: np.ndarray) -> np.ndarray:
  """The mean over tasks of each task's mean over runs (rliable's `metrics.aggregate_mean`)."""
  return scores.mean(axis=0).mean(axis=0)


def improvement(x: np.ndarray, y: np.ndarray) -> np.ndarray:
  """P(X > Y): the chance that a run of X scores above a run of Y on a task (ties count
  half), averaged over tasks (rliable's `metrics.probability_of_improvement`)."""
  above = (x[:, None] > y[None]).mean(axis=(0, 1))
  tied = (x[:, None] == y[None]).mean(axis=(0, 1))
  return (above + 0.5 * tied).mean(axis=0)


def score_distribution(scores: np.ndarray, levels: np.ndarray) -> np.ndarray:
  """The fraction of runs x tasks scoring above each level (rliable's score distribution);
  for several scores, their profiles one after the other."""
  above = scores[..., None] > levels  # runs x tasks (x scores) x levels
  return above.mean(axis=(0, 1)).reshape(-1)


# -- their intervals --------------------------------------------------------------
_seed = [SEED]  # the bootstrap's seed now: SEED, or another under `bootstrap_seed`


@contextlib.contextmanager
def bootstrap_seed(seed: int):
  """Every interval computed inside bootstraps from `seed`: whether a verdict is the
  bootstrap's or the data's (results_page reads each at several seeds)."""
  _seed.append(seed)
  try:
    yield
  finally:
    _seed.pop()


@contextlib.contextmanager
def _seeded():
  """NumPy's global random state at the bootstrap's seed for rliable, restored afterwards."""
  state = np.random.get_state()
  np.random.seed(_seed[-1])
  try:
    yield
  finally:
    np.random.set_state(state)


def _stack(scores: dict[str, np.ndarray]) -> np.ndarray:
  """{name: runs x tasks} as one runs x tasks x scores array."""
  matrices = [np.asarray(m, float) for m in scores.values()]
  if not matrices or any(m.ndim != 2 or 0 in m.shape or m.shape != matrices[0].shape
                         for m in matrices):
    raise BadInput("scores must be runs x tasks matrices of one shape, "
                   f"not {[m.shape for m in matrices]}")
  return np.stack(matrices, axis=-1)


def _intervals(data, func, reps: int) -> tuple[np.ndarray, np.ndarray]:
  """rliable's stratified bootstrap of `func` over `data` (one array, or a list of arrays
  resampled independently): the point estimates and a (2, k) array of bounds."""
  from rliable import library

  with _seeded():
    points, bounds = library.get_interval_estimates(
        {"x": data}, func, reps=reps, confidence_interval_size=CONFIDENCE)
  return np.asarray(points["x"], float), np.asarray(bounds["x"], float)


def _estimates(points: np.ndarray, bounds: np.ndarray) -> list[Estimate]:
  return [Estimate(float(p), float(lo), float(hi)) for p, lo, hi in zip(points, *bounds)]


def aggregates(scores: dict[str, np.ndarray],
               reps: int = REPS) -> dict[str, tuple[Estimate, Estimate]]:
  """Per score, the IQM and the mean over runs x tasks, each with its interval."""
  func = lambda s: np.concatenate([iqm(s), mean(s)])
  found = _estimates(*_intervals(_stack(scores), func, reps))
  return {name: (found[i], found[len(scores) + i]) for i, name in enumerate(scores)}


def probability_of_improvement(x: dict[str, np.ndarray], y: dict[str, np.ndarray],
                               reps: int = REPS) -> dict[str, Estimate]:
  """Per score, P(X > Y) of two methods' runs x tasks matrices (the same tasks, any number
  of runs each), with its interval (each method's runs resampled on their own)."""
  a, b = _stack(x), _stack({name: y[name] for name in x})
  if a.shape[1:] != b.shape[1:]:
    raise BadInput(f"the two methods' scores have {a.shape[1]} and {b.shape[1]} tasks")
  return dict(zip(x, _estimates(*_intervals([a, b], improvement, reps))))


def performance_profile(scores: dict[str, np.ndarray], levels,
                        reps: int = REPS) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
  """Per score, the performance profile at `levels`: the fraction of runs x tasks above
  each level, its lower and its upper bound (three arrays of the levels' length)."""
  from rliable import library

  levels = np.asarray(levels, float)
  with _seeded():
    profile, bounds = library.create_performance_profile(
        {"x": _stack(scores)}, levels, custom_profile_func=score_distribution, reps=reps,
        confidence_interval_size=CONFIDENCE)
  split = lambda a: np.asarray(a, float).reshape(len(scores), len(levels))
  found = zip(split(profile["x"]), split(bounds["x"][0]), split(bounds["x"][1]))
  return dict(zip(scores, found))


# -- reading P(X > Y) ---------------------------------------------------------------
def verdict(p: Estimate, centre: float = 0.5) -> str:
  """Where P(default > row) stands: above or below 0.5 when its interval is, else not
  separated (a difference of means: against 0)."""
  if p.low > centre:
    return "above"
  if p.high < centre:
    return "below"
  return "not separated"


def difference(x: np.ndarray, y: np.ndarray) -> np.ndarray:
  """mean(X) - mean(Y): each the mean over tasks of the mean over runs."""
  return mean(x) - mean(y)


def mean_difference(x: dict[str, np.ndarray], y: dict[str, np.ndarray],
                    reps: int = REPS) -> dict[str, Estimate]:
  """Per score, the mean of X's runs x tasks matrix minus Y's, with its interval (each
  method's runs resampled on their own, within each task): where tasks that both solve tie,
  a difference the probability of improvement dilutes."""
  a, b = _stack(x), _stack({name: y[name] for name in x})
  if a.shape[1:] != b.shape[1:]:
    raise BadInput(f"the two methods' scores have {a.shape[1]} and {b.shape[1]} tasks")
  return dict(zip(x, _estimates(*_intervals([a, b], difference, reps))))


def seeds_for(spread_x: float, spread_y: float, effect: float, runs_y: int | None = None,
              power: float = 0.8) -> int:
  """The runs of X needed for the 95 % interval of mean(X) - mean(Y) to clear 0 with
  probability `power` where the true difference is `effect`, the runs' scores spreading
  by these standard deviations (normal approximation): the least n with
  effect / sqrt(sx^2 / n + sy^2 / m) >= 1.96 + z(power); `runs_y` m the runs of Y already
  there (None: as many as X's)."""
  from statistics import NormalDist

  need = NormalDist().inv_cdf(0.975) + NormalDist().inv_cdf(power)
  for n in range(2, 1000):
    m = n if runs_y is None else runs_y
    if effect / math.sqrt(spread_x ** 2 / n + spread_y ** 2 / m) >= need:
      return n
  raise BadInput(f"no run count up to 1000 separates an effect of {effect} with "
                 f"{runs_y} runs of the other row")


def seeds_to_separate(p: Estimate, seeds: int) -> int | None:
  """The seeds (per row) at which the interval of P would clear 0.5 if the gap held: its
  half-width towards 0.5 shrinks as 1/sqrt(seeds), so the first n' with
  half-width * sqrt(n / n') < gap. None for no gap (P = 0.5)."""
  gap = abs(p.value - 0.5)
  if gap < 1e-9:  # a mean of fractions that is 0.5 up to rounding
    return None
  half_width = p.value - p.low if p.value > 0.5 else p.high - p.value
  return math.floor(seeds * (half_width / gap) ** 2) + 1
