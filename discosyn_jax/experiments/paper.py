"""The paper's experiments as plans of steps, each at a scale: `discosyn experiment NAME`.

  discosyn-set1 / -set2  DiscoSyn<b>-L and -NL (Tables I and II), each followed by its
                         controls (what the learned decoder must beat): Random<b>-L / -NL,
                         the same run with the decoder frozen at its random initialisation;
                         Random<b>-L-zfree / -NL-zfree, the same with z free (not squashed);
                         Random<b>-L-matched, the random subspace of that start carrying the
                         learned decoder's singular values, bias and noise (isolates the
                         subspace from its scale and offset; read from the DiscoSyn run)
  discosyn-planted /     the same on the planted-synergy test bed (discosyn_jax/tasks/planted.py, b = 3):
    -planted_slack       one adequate subspace / many; not part of `all`. Also DiscoSyn3-L
                         with the annealed decoder weight decay (DiscoSyn3-L-wd8a200, the
                         `-decay` preset) and its Random3-L-matched-wd8a200 control
  baselines-set1 / -set2 the sequential baseline: independent full-action PPO per task (one
                         run, one head and one value net per task, no shared parameters),
                         its deterministic actions collected, PCA and an autoencoder fitted
                         for k = 3, 4, 6, then policies trained in the frozen PCA4, AE4, PCA6,
                         AE6 spaces (a = the decoder's mean, no noise outside the space)
  transfer               unseen tasks with a frozen DiscoSyn decoder, each seed's default
                         (set #1's DiscoSyn3-L-reward for the two valves, set #2's
                         DiscoSyn6-L-reward for the top-down screw), beside a frozen random
                         decoder of the same size (z bounded, and z free) and full-action
                         PPO from scratch on the same tasks and budget
  sparse                 the sparse goal valve: the same rows, from set #1's decoder
                         (transfer and sparse then the same again from the residual row's
                         decoder, DiscoSyn<b>-L-reward-res..., each frozen run and its
                         controls acting with that residual; not part of `all`)
  table1 / table2        a table's rows with today's defaults (PAPER_ROWS, not every start
                         and control discosyn-<set> tries): DiscoSyn, its controls and the
                         sequential baselines, the same steps and folders as in `all`
  all                    table1, the sparse valve, transfer, table2 (last: its runs are the
                         long ones)

Every step writes into its own folder of OUT (`<method>-<set>-seed<n>`). A step whose folder
holds a finished run of the same config is kept, whether by its final checkpoint or by its
record alone (discosyn_jax/experiments/record.py: what a run ends by writing, and what `discosyn keep`
copies to be committed); an unfinished one is resumed, so an interrupted `all` is continued
by running it again, in a fresh clone from the committed records too. A later step reads
the records of those before it (decoder.npz, a fit's synergy files); only a fit reads a
checkpoint (it rolls out its PPO run: one kept as a record alone, as in a fresh clone, is
trained again, from step 0, before its fit). Each run folder gets an `experiment.json`
(experiment, method, set, seed, scale) that `discosyn report` reads.

One file over 300 lines on purpose: the steps (Train, Fit, Match) and the plans built from
them are read together, as the plan of an experiment is its list of steps.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
from typing import Any, ClassVar

import jax
import numpy as np

from discosyn_jax import assemble, decoders, tasks
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import hands
from discosyn_jax.run import layout
from discosyn_jax.synergies import fitting
from discosyn_jax.training import evaluation
from discosyn_jax.experiments import presets, record, rows
from discosyn_jax.experiments.method import Method, Residual

# the task sets of discosyn_jax/tasks/sets.py, the unseen tasks split by the set whose synergies they take
TASK_SETS = {**{name: tasks.TASK_SETS[name] for name in ("set1", "set2", "sparse", "planted",
                                                         "planted_slack")},
             "unseen-set1": ("valve_cylinder", "valve_cw"), "unseen-set2": ("screw_topdown",)}
DISCOSYN_SIZES = {"set1": (3, 4), "set2": (4, 6), "planted": (3,), "planted_slack": (3,)}
BASELINES = (("PCA", 4), ("AE", 4), ("PCA", 6), ("AE", 6))  # trained in, as in the paper
FITTED_SIZES = (3, 4, 6)  # explained variance reported for these
# each seed's default decoder (the preset's start: the reward prior): the same run, in the
# same folder, as that set's DiscoSyn<b>-L-reward row
TRANSFER_FROM = {"unseen-set1": ("set1", Method.parse("DiscoSyn3-L-reward")),
                 "unseen-set2": ("set2", Method.parse("DiscoSyn6-L-reward")),
                 "sparse": ("set1", Method.parse("DiscoSyn3-L-reward"))}
# the rows of the paper's Tables I and II with today's defaults, what `all` runs of
# discosyn-<set> and baselines-<set>: DiscoSyn from each set's default start (the paper's
# DiscoSyn<b>-L is today's DiscoSyn<b>-L-reward), the controls it must beat (a random
# decoder frozen, z bounded and z free; the prior's start frozen), the sequential baselines
PAPER_ROWS = {
    "set1": ("DiscoSyn3-L-reward", "DiscoSyn4-L-reward", "DiscoSyn3-NL", "DiscoSyn4-NL",
             "Random3-L", "Random3-L-zfree", "Prior3-L-reward", "Random4-L", "Random4-L-zfree",
             "Prior4-L-reward", "Random3-NL-zfree", "Random4-NL-zfree",
             "PPO", "PCA4", "AE4", "PCA6", "AE6"),
    "set2": ("DiscoSyn6-L-reward", "DiscoSyn4-L-reward", "DiscoSyn6-NL", "DiscoSyn4-NL",
             "Random6-L", "Random6-L-zfree", "Prior6-L-reward",
             "PPO", "PCA4", "AE4", "PCA6", "AE6"),
}
PAPER_ROWS = {task_set: tuple(map(Method.parse, rows)) for task_set, rows in PAPER_ROWS.items()}


@dataclasses.dataclass(frozen=True)
class Scale:
  train: dict[str, Any]  # TrainConfig fields
  collect_episodes: int  # deterministic episodes per task behind PCA / autoencoder
  autoencoder_steps: int
  seeds: tuple[int, ...]  # the seeds an experiment runs unless told otherwise
  # task sets that need a larger budget: the fields of `train` their runs change
  per_set: dict[str, dict[str, Any]] = dataclasses.field(default_factory=dict)

  def train_for(self, task_set: str) -> dict[str, Any]:
    return {**self.train, **self.per_set.get(task_set, {})}


SCALES = {
    # seconds per run: the pipeline's plumbing, nothing learned
    "ci": Scale(dict(num_envs=4, unroll_length=5, num_minibatches=2, update_epochs=1, steps=2,
                     eval_every=1, eval_envs=2, closing_episodes=4, checkpoint_every=0), 2, 50,
                (0,)),
    # a 2-core CPU: 1.5 M env steps for a four-task run of set #1, 4-6 min with two runs side
    # by side; Table I at this scale (17 runs and a fit a seed) takes 1.5 h a seed, two seeds
    # side by side (2026-12-03), the sparse valve and transfer ~30 min a seed more.
    # Set #2 trains 4x as long (6.1 M env steps, 36-52 min a run two side by side): full-action
    # PPO needs that for the dice (80 % at 2.8 M / 5.4 M env steps on 2 seeds of 3; at 1x it
    # stands at 0.50, docs/notes/2026-12-03-a-reward-prior.md "A budget for set #2").
    "cpu": Scale(dict(num_envs=64, unroll_length=20, num_minibatches=4, update_epochs=4,
                      steps=300, eval_every=50, eval_envs=32, checkpoint_every=100), 32, 3000,
                 (0, 1, 2), per_set={"set2": dict(steps=1200, checkpoint_every=200)}),
    # the `cpu` scale trained 8x as long (12.3 M env steps for set #1, 49 M for set #2), its
    # evaluations as often: with a constant learning rate and nothing scheduled by the run's
    # length in the paper's rows, one long run's curve gives its success at every budget up
    # to 8x (the budget study of the paper's rows; not bit for bit the `cpu` run of its seed:
    # docs/notes/2026-12-07-c-own-synergies.md)
    "long": Scale(dict(num_envs=64, unroll_length=20, num_minibatches=4, update_epochs=4,
                       steps=2400, eval_every=50, eval_envs=32, checkpoint_every=200), 32, 3000,
                  (0, 1, 2), per_set={"set2": dict(steps=9600, checkpoint_every=400)}),
    # one GPU: 2048 envs per task, 98 M env steps for a four-task run (~26 min on an H200 at
    # its 64k env steps/s, ready in ~3.5 min, 2026-12-04; set #1's default trained to
    # 0.95-1.00 by 18.8 M); episodes restart from a pool of initial states, so the train step
    # compiles no mjx.forward (BENCHMARKS.md, "GPU")
    "gpu": Scale(dict(num_envs=2048, unroll_length=20, num_minibatches=16, update_epochs=4,
                      reset_pool=True, steps=600, eval_every=25, eval_envs=256, checkpoint_every=100), 256, 20000,
                 (0, 1, 2)),
}


# -- steps ---------------------------------------------------------------------
@dataclasses.dataclass
class Train:
  name: str  # the run's folder in OUT
  config: TrainConfig
  meta: dict[str, Any]
  needs: tuple[str, ...] = ()  # the steps whose folders this one reads

  @property
  def method(self) -> Method:
    return Method.parse(self.meta["method"])

  def done(self, out: pathlib.Path) -> bool:
    """A finished run of this config: its final checkpoint, or its record alone."""
    return record.finished(out / self.name, self.config)

  def run(self, out: pathlib.Path, progress: bool, log) -> None:
    run_dir = out / self.name
    resume = (run_dir / layout.CONFIG_FILE).is_file()
    done = assemble.train(self.config, run_dir, resume=resume, progress=progress, log=log)
    self.label(out)
    record.write(run_dir, done["trainer"], done["state"])

  def settle(self, out: pathlib.Path, log) -> None:
    """Complete what a finished run lacks: the lock and curves a writer killed after its
    final checkpoint left (assemble.finish), its experiment.json (a run of the same config
    that `discosyn train` made in this folder), the files of its record a run finished
    before records were written lacks (from its final checkpoint)."""
    run_dir = out / self.name
    assemble.finish(run_dir, log)  # a writer killed after its final checkpoint: lock, curves
    if not (run_dir / layout.EXPERIMENT_FILE).is_file():
      self.label(out)
    if not record.complete(run_dir, record.saved_config(run_dir)):
      log(f"[{self.name}] its record, from its final checkpoint")
      record.write(run_dir, *assemble.load(run_dir / layout.FINAL))

  def label(self, out: pathlib.Path) -> None:
    """Write the run's experiment.json: what `discosyn report` reads of it."""
    (out / self.name / layout.EXPERIMENT_FILE).write_text(json.dumps(self.meta, indent=1))


@dataclasses.dataclass
class FromRun:
  """A step that writes FILE into its folder from a run's (`source`): done once it is there."""
  name: str  # its folder in OUT
  source: str  # the run's folder in OUT
  FILE: ClassVar[str]

  @property
  def needs(self) -> tuple[str, ...]:
    return (self.source,)

  def done(self, out: pathlib.Path) -> bool:
    return (out / self.name / self.FILE).is_file()


@dataclasses.dataclass
class Fit(FromRun):
  """Collect a full-action run's deterministic actions; fit PCA and autoencoders to them
  (synergy files in its folder)."""
  episodes: int
  autoencoder_steps: int
  hidden: tuple[int, ...]
  meta: dict[str, Any]
  FILE = record.FIT_FILE  # written last: its presence marks the step done

  def run(self, out: pathlib.Path, progress: bool, log) -> None:
    trainer, state = assemble.load(out / self.source)
    config = trainer.config
    key = jax.random.PRNGKey(config.seed + 2)
    rollouts = evaluation.rollouts(trainer, state.params, state.normalizers, key, self.episodes)
    per_task = fitting.applied_actions(rollouts)
    actions = np.concatenate(list(per_task.values()))
    folder = out / self.name
    folder.mkdir(parents=True, exist_ok=True)
    np.savez(folder / record.ACTIONS_FILE, **per_task)
    variance: dict[str, Any] = {**self.meta, "samples": int(actions.shape[0]), "PCA": {}, "AE": {}}
    for k in FITTED_SIZES:
      if k > min(actions.shape):
        log(f"{self.name}: {actions.shape[0]} actions are too few for {k} synergies; skipped")
        continue
      for method, fit in (
          ("PCA", lambda: fitting.fit_pca(actions, k)),
          ("AE", lambda: fitting.fit_autoencoder(actions, k, self.hidden,
                                                   steps=self.autoencoder_steps, seed=config.seed))):
        params, ev = fit()
        fitting.save(folder / f"{method.lower()}{k}.npz", params,
                       fitted_meta(method, k, self.hidden), method=method,
                       explained_variance=ev, source=self.source)
        variance[method][str(k)] = ev
        log(f"{self.name}: {method}{k} explains {ev:.1%} of the action variance")
    # written last: its presence marks the step done
    (folder / record.FIT_FILE).write_text(json.dumps(variance, indent=1))


def fitted_meta(method: str, k: int, hidden: tuple[int, ...]) -> dict[str, Any]:
  """The meta of a fitted synergy file: the decoder it is, and the method that made it."""
  kind = decoders.LINEAR if method == "PCA" else decoders.MLP
  return dict(decoder=kind.name, n_synergies=k, decoder_bias=True, decoder_hidden=hidden,
              method=method)


@dataclasses.dataclass
class Match(FromRun):
  """Write the decoder of a `-matched` control: the random initial subspace of a linear
  DiscoSyn run's seed carrying that run's learned singular values, bias and noise (read
  from the record of that run)."""
  meta: dict[str, Any]
  FILE = layout.DECODER_FILE

  def run(self, out: pathlib.Path, progress: bool, log) -> None:
    from discosyn_jax.agent import networks

    config = record.saved_config(out / self.source)
    meta, learned = fitting.read(out / self.source / layout.DECODER_FILE)
    start = networks.random_decoder(config, int(np.shape(learned["log_std"])[-1]))
    fitting.save(out / self.name / self.FILE, fitting.in_subspace_of(learned, start),
                   meta, source=self.source)
    log(f"{self.name}: the learned decoder of {self.source} in its random initial subspace")


# -- plans ---------------------------------------------------------------------
def _meta(experiment, method: Method | str, task_set, seed, scale):
  """A step's experiment.json: a run's method by name, "fit" for a fit's folder."""
  return dict(experiment=experiment, method=str(method), set=task_set, seed=seed, scale=scale)


class Planner:
  """The steps of each experiment at one scale and seed, folders named in OUT."""

  def __init__(self, out: pathlib.Path, scale: str, seed: int, task_sets=None, decoder_from=None,
               hand: str = hands.DEFAULT):
    if scale not in SCALES:
      raise BadInput(f"unknown scale {scale!r}; scales: {', '.join(SCALES)}")
    self.out, self.scale, self.seed, self.hand = pathlib.Path(out), scale, seed, hand
    # folders end in seed<n>, or <hand>-seed<n> on another hand than ours
    self.tag = (f"{hands.label(hand)}-" if hand != hands.DEFAULT else "") + f"seed{seed}"
    self.sets = {**TASK_SETS, **(task_sets or {})}
    self.sizes = SCALES[scale]
    self.decoder_from = decoder_from  # transfer / sparse: this decoder instead of their own run

  def _config(self, base: TrainConfig, task_set: str, **changes) -> TrainConfig:
    return base.replace(tasks=tuple(self.sets[task_set]), seed=self.seed, hand=self.hand,
                        **self.sizes.train_for(task_set), **changes).validate()

  def _folder(self, method: Method | str, task_set: str) -> str:
    return f"{str(method).lower()}-{task_set}-{self.tag}"

  def row(self, method: Method, task_set: str) -> TrainConfig:
    """The config of row `method` on `task_set` at this scale and seed (rows.config_for)."""
    return rows.config_for(method, task_set, tasks=tuple(self.sets[task_set]), seed=self.seed,
                           hand=self.hand, **self.sizes.train_for(task_set))

  def with_residual(self, method: Method, task_set: str) -> Method:
    """`method` beside the preset residual (presets.RESIDUAL: its ramp a share of the run),
    in this scale's train steps."""
    steps = self.sizes.train_for(task_set)["steps"]
    return method.replace(residual=Residual(presets.RESIDUAL_CAP,
                                            round(presets.RESIDUAL["residual_ramp"] * steps)))

  def learned_rows(self, task_set: str) -> list[Method]:
    """The DiscoSyn rows of discosyn-<set>: on the hand's sets the paper's random start, the
    mlp decoder, both priors' starts and the reward prior's beside a residual; on the test
    bed the paper's, the mlp and the decayed variant (measured to work there,
    docs/notes/2026-12-02-a-planted-test-bed.md)."""
    linear, mlp = decoders.LINEAR.letter, decoders.MLP.letter
    out = []
    for b in DISCOSYN_SIZES[task_set]:
      paper, reward = Method("DiscoSyn", b, linear), Method("DiscoSyn", b, linear, start="reward")
      if task_set in presets.DECAYED_SETS:
        out += [paper, Method("DiscoSyn", b, mlp),
                paper.replace(decay=presets.DECAY["decoder_weight_decay"],
                              decay_steps=presets.DECAY["decoder_weight_decay_steps"])]
      else:
        out += [paper, Method("DiscoSyn", b, mlp), paper.replace(start="objects"), reward,
                self.with_residual(reward, task_set)]
    return out

  def discosyn(self, task_set: str, method: Method) -> Train:
    config = self.row(method, task_set)
    method = Method.of(config)
    return Train(self._folder(method, task_set), config,
                 _meta(f"discosyn-{task_set}", method, task_set, self.seed, self.scale))

  def random_decoder(self, learned: Train, task_set: str, experiment: str) -> Train:
    """The control of a DiscoSyn run (or a frozen learned space): the same config with its
    decoder frozen at its random initialisation (the decoder the DiscoSyn run of this seed
    starts from, whatever the tasks)."""
    config = learned.config.replace(freeze_decoder=True, decoder_from="", decoder_weight_decay=0.0,
                                    decoder_weight_decay_steps=0, decoder_init="random").validate()
    method = Method.of(config)
    return Train(self._folder(method, task_set), config,
                 _meta(experiment, method, task_set, self.seed, self.scale))

  def zfree(self, random: Train, name: str = "") -> Train:
    """The control `random` with z free (the stronger of the two): the same frozen decoder,
    the heads' z unbounded; in folder `name`, else in its method's."""
    method = random.method.replace(control="zfree")
    return Train(name or self._folder(method, random.meta["set"]),
                 random.config.replace(squash_z=False).validate(), {**random.meta, "method": str(method)})

  def controls(self, learned: Train, task_set: str, experiment: str) -> list:
    """A DiscoSyn run's controls (module docstring): Random, Random-zfree where the run
    bounds z, and for a linear decoder Random-matched with the step that writes its decoder."""
    random = self.random_decoder(learned, task_set, experiment)
    steps = [random]
    meta = lambda method: _meta(experiment, method, task_set, self.seed, self.scale)
    if learned.config.squash_z:
      steps.append(self.zfree(random))
    if learned.config.decoder_init != "random":  # the prior's start frozen: what learning adds
      prior = random.config.replace(decoder_init=learned.config.decoder_init).validate()
      method = Method.of(prior)
      steps.append(Train(self._folder(method, task_set), prior, meta(method)))
    if learned.config.kind.linear:
      # named after the learned run it copies: Random3-L-matched, Random3-L-matched-wd8a200
      method = learned.method.replace(family="Random", control="matched")
      match = Match(self._folder(f"{method}-decoder", task_set), learned.name, meta("fit"))
      path = (self.out / match.name / Match.FILE).resolve()
      steps += [match, Train(self._folder(method, task_set),
                             random.config.replace(decoder_from=str(path)).validate(),
                             meta(method), needs=(match.name,))]
    return steps

  def ppo(self, task_set: str, experiment: str) -> Train:
    return Train(self._folder("PPO", task_set), self.row(Method("PPO"), task_set),
                 _meta(experiment, "PPO", task_set, self.seed, self.scale))

  def baselines(self, task_set: str) -> list:
    experiment = f"baselines-{task_set}"
    ppo = self.ppo(task_set, experiment)
    hidden = ppo.config.decoder_hidden
    fit = Fit(self._folder("synergies", task_set), ppo.name, self.sizes.collect_episodes,
              self.sizes.autoencoder_steps, hidden, _meta(experiment, "fit", task_set, self.seed,
                                                          self.scale))
    steps = [ppo, fit]
    for method, k in BASELINES:
      frozen = fitting.frozen_fields(fitted_meta(method, k, hidden),
                                       self.out / fit.name / f"{method.lower()}{k}.npz")
      config = self._config(ppo.config, task_set, init_z_std=1.0, **frozen)
      steps.append(Train(self._folder(f"{method}{k}", task_set), config,
                         _meta(experiment, f"{method}{k}", task_set, self.seed, self.scale),
                         needs=(fit.name,)))
    return steps

  def frozen_synergies(self, task_set: str, experiment: str, variant: str = "") -> list:
    """The source DiscoSyn run, then a frozen-decoder run, its random controls and a
    full-action run on `task_set`. `variant`: the source row's preset suffix; with
    RESIDUAL_SUFFIX the source learned beside a residual, and the frozen run and its
    controls act with the same cap, ramped in over the first half of their own run (as the
    source's was over its)."""
    source_set, row = TRANSFER_FROM[task_set]
    if variant == presets.RESIDUAL_SUFFIX:
      row = self.with_residual(row, source_set)
    base = self.row(row, source_set)
    if self.decoder_from:
      meta, _ = fitting.read(self.decoder_from)
      source, path, method = None, self.decoder_from, Method.of(meta)
    else:
      source = self.discosyn(source_set, row)
      meta, method = fitting.meta_of(source.config), source.method
      path = self.out / source.name / layout.DECODER_FILE  # the record of its run
    changes = fitting.frozen_fields(meta, path)
    if base.residual:
      if not changes["decoder_noise"]:
        return []  # a fitted space (--decoder-from) acts with its mean: no noise for a residual
      changes["residual_ramp"] = 0.5
    config = self._config(base, task_set, **changes)
    # named by its source row and its own residual: "DiscoSyn3-L-reward frozen",
    # "DiscoSyn3-L-reward-res0.3r150 frozen-res0.3r150"
    method = method.replace(reuse="frozen", acting_residual=Residual.of(config))
    # folders: transfer-synergies-set1-seed0 (unseen tasks of set #1), sparse-synergies-seed0,
    # transfer-synergies-residual-set1-seed0
    label = task_set.removeprefix("unseen-")
    folder = lambda what, variant=variant: (
        f"{experiment}-{what}{variant}-{self.tag}" if label == experiment
        else self._folder(f"{experiment}-{what}{variant}", label))
    frozen = Train(folder("synergies"), config,
                   _meta(experiment, method, task_set, self.seed, self.scale),
                   needs=(source.name,) if source else ())
    # one full-action run for every variant
    scratch = dataclasses.replace(self.ppo(task_set, experiment), name=folder("ppo", ""))
    # the learned space against a random one of the same size, z bounded as it is, and z
    # free: the stronger of the two is the control
    random = dataclasses.replace(self.random_decoder(frozen, task_set, experiment),
                                 name=folder("random"))
    controls = [random] + ([self.zfree(random, folder("random-zfree"))]
                           if random.config.squash_z else [])
    return [step for step in (source, frozen, *controls, scratch) if step is not None]

  def frozen_rows(self, experiment: str, variants=("",)) -> list:
    """transfer (the unseen tasks of both sets) or sparse, once per source variant; the
    steps two variants share (the full-action run) once."""
    sets = ("unseen-set1", "unseen-set2") if experiment == "transfer" else ("sparse",)
    steps = [step for variant in variants for task_set in sets
             for step in self.frozen_synergies(task_set, experiment, variant)]
    return list({step.name: step for step in steps}.values())

  def plan(self, experiment: str) -> list:
    if experiment in TABLES:  # one table's rows: a part of `all`, hours rather than a day on 2 cores
      task_set = TABLES[experiment]
      planned = self.plan(f"discosyn-{task_set}") + self.plan(f"baselines-{task_set}")
      known = {step.method for step in planned if isinstance(step, Train)}
      # a row the experiments do not train is composed from its name (rows.config_for)
      added = [self.discosyn(task_set, m) for m in PAPER_ROWS[task_set] if m not in known]
      return select(planned + added, PAPER_ROWS[task_set])
    if experiment == "all":  # set #2 last: its runs are the long ones
      parts = [self.plan("table1"), self.frozen_rows("sparse"), self.frozen_rows("transfer"),
               self.plan("table2")]
      steps: dict[str, Any] = {}  # a step parts share (the decoder transfer freezes) runs once
      for step in (step for part in parts for step in part):
        steps.setdefault(step.name, step)
      return list(steps.values())
    family, _, task_set = experiment.partition("-")  # discosyn-<set>, baselines-<set>
    if family == "discosyn" and task_set in DISCOSYN_SIZES:
      runs = [self.discosyn(task_set, method) for method in self.learned_rows(task_set)]
      steps = [step for run in runs for step in (run, *self.controls(run, task_set, experiment))]
      return list({step.name: step for step in steps}.values())  # one Random<b>-L for both
    if family == "baselines" and task_set in DISCOSYN_SIZES:
      return self.baselines(task_set)
    if experiment in ("transfer", "sparse"):  # the paper's rows, then the residual's
      return self.frozen_rows(experiment, ("", presets.RESIDUAL_SUFFIX))
    raise BadInput(f"unknown experiment {experiment!r}; experiments: {', '.join(EXPERIMENTS)}")


TABLES = {"table1": "set1", "table2": "set2"}  # the paper's tables: PAPER_ROWS of a set
EXPERIMENTS = ("discosyn-set1", "discosyn-set2", "baselines-set1", "baselines-set2", "transfer",
               "sparse", *TABLES, "all", "discosyn-planted", "discosyn-planted_slack")


def select(steps: list, methods) -> list:
  """The steps of these methods (e.g. "DiscoSyn3-L", "PCA4", "DiscoSyn3-L frozen") and the
  steps they read from (a PCA row's PPO run and fit, a frozen space's DiscoSyn run), in plan
  order."""
  by_name, methods = {s.name: s for s in steps}, set(methods)
  keep = {s.name for s in steps if isinstance(s, Train) and s.method in methods}
  todo = list(keep)
  while todo:
    for need in by_name[todo.pop()].needs:
      if need in by_name and need not in keep:
        keep.add(need)
        todo.append(need)
  return [s for s in steps if s.name in keep]


def run(experiment: str, out: pathlib.Path, scale: str, seeds=None, *,
        task_sets=None,
        decoder_from=None, methods=None, hand: str = hands.DEFAULT, progress: bool = False,
        log=print) -> list[pathlib.Path]:
  """Run (or continue) one experiment for every seed on `hand` (a shipped hand or an MJCF
  file, hands.load); the folders of its steps.

  `decoder_from` (a run folder or a synergy file) gives transfer and sparse a decoder
  trained elsewhere instead of their own DiscoSyn run. `methods`: only these methods' steps
  and the steps they need (more seeds of some rows, say)."""
  if decoder_from and experiment not in ("transfer", "sparse"):
    raise BadInput(f"a decoder can be given to transfer and sparse only, not to {experiment}")
  out = pathlib.Path(out)
  if seeds is None:
    seeds = SCALES[scale].seeds if scale in SCALES else (0,)
  hand = hands.load(hand).name  # a file's absolute path
  plans = [Planner(out, scale, seed, task_sets, decoder_from, hand).plan(experiment) for seed in seeds]
  if methods:
    methods = [Method.parse(m) if isinstance(m, str) else m for m in methods]
    known = {s.method for s in plans[0] if isinstance(s, Train)}
    unknown = [m.name for m in methods if m not in known]
    if unknown:
      raise BadInput(f"{experiment} has no method {', '.join(map(repr, unknown))}; its methods: "
                     f"{', '.join(sorted(m.name for m in known))}")
    plans = [select(steps, methods) for steps in plans]
  folders = []
  for steps in plans:
    again = _trained_again(steps, out)
    for step in steps:
      folders.append(out / step.name)
      if step.name in again:
        log(f"[{step.name}] finished, but its record alone is here: its fit rolls out the "
            f"trained policy, which only a checkpoint keeps; trained again")
      elif step.done(out):
        log(f"[{step.name}] done already; kept")
        if isinstance(step, Train):
          step.settle(out, log)
        continue
      log(f"[{step.name}] {type(step).__name__.lower()}")
      step.run(out, progress, log)
  return folders


def _trained_again(steps: list, out: pathlib.Path) -> set[str]:
  """The full-action runs an unfinished fit reads that are finished by their record alone
  (no final checkpoint): the fit needs the policy, which a record does not keep. An
  unfinished one is not among them: it is trained (or resumed) as any step."""
  by_name = {step.name: step for step in steps}
  return {step.source for step in steps if isinstance(step, Fit) and not step.done(out)
          and by_name[step.source].done(out) and not (out / step.source / layout.FINAL).is_dir()}
