"""The typed configuration of a training run, and its checks.

One frozen dataclass holds everything a run depends on; presets (discosyn_jax/experiments/presets.py)
are instances of it, command-line flags replace fields. The same config rebuilds the
network and the environments when a run is resumed or evaluated.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import io
import json
import pathlib
import tokenize
from typing import Any

from discosyn_jax import atomic, checks, decoders
from discosyn_jax.checks import BadInput
from discosyn_jax.env.settings import PHYSICS  # the env's choice a config names

# the priors a linear decoder may start from (decoder_init): what the pushed actions are read
# by, and how the tasks' metrics make one subspace (discosyn_jax/synergies/priors.py)
PRIORS = {"objects": ("objects", "trace"), "reward": ("reward", "share")}
# a start's name in the files of older releases: the objects prior was "physics" until
# 2026-12-05 (config files and synergy files are read with today's name)
OLD_STARTS = {"physics": "objects"}
# decoder_init as config.json writes it where the decoder is read from decoder_from: the
# start is that decoder (in memory "random", the start of no prior: what the code compares)
GIVEN_START = "decoder_from"
DECODER_INITS = ("auto", "random", *PRIORS)
# what q(.|a) reads back from an action: the head's z (the paper's), or the activation the
# decoder read, tanh(z) where z is bounded (the same as z where it is not)
DISCRIMINATOR_TARGETS = ("z", "activation")

# Fields that may differ between a run and its resumption: they change how long and how
# often, never what the state holds.
RESUMABLE = frozenset({"steps", "eval_every", "eval_envs", "checkpoint_every", "keep_checkpoints",
                       "closing_episodes"})
# Fields that change neither the state nor the logs of the training run itself: a finished
# run is the run of a config that differs from its own in these alone (record.finished)
AFTER_THE_RUN = frozenset({"closing_episodes"})
MAX_STEPS = 2**31 - 1  # the state counts train steps in an int32
# Fields added since the first release, each with the value every run before it had: a
# config.json without them is refused (never filled with today's default) until
# `discosyn upgrade RUN` writes these values into it (upgrade below).
ADDED = {"squash_z": False, "physics": "reference", "reset_pool": False, "decoder_weight_decay": 0.0,
         "decoder_weight_decay_steps": 0, "hand": "shadow20",
         "decoder_init": "random", "discriminator_target": "z", "task_posture": False,
         "residual": 0.0, "residual_ramp": 0.0, "residual_start": 0.0,
         "init_residual_std": 0.05, "closing_episodes": 0, "z_std_floor": 0.0,
         "task_noise": False, "bonus_cap": False, "own_synergies": 0}
# Fields renamed since a release, read by what they became: the residual's schedule was in
# train steps until 2026-12-05 and is a share of the run's `steps` since (the same run)
RENAMED = {"residual_ramp_steps": "residual_ramp", "residual_start_steps": "residual_start"}


@dataclasses.dataclass(frozen=True)
class TrainConfig:
  # Each field's comment (the lines right above it and the one beside it) is its
  # documentation: `discosyn train --help` shows it (field_docs below). "# -- " heads a group.
  # -- what is learned --
  # tasks or task sets, e.g. set1 valve_cw (`discosyn tasks` lists them)
  tasks: tuple[str, ...] = ("valve0", "valve1", "valve2", "valve3")
  # the hand: shadow20 (ours, the paper's), leap16 (a LEAP-like four-finger hand), or an MJCF
  # file of one's own, path/to/hand.xml[:PALM_SITE] (docs/YOUR_HAND.md)
  hand: str = "shadow20"
  # synergy count b, the size of z (1-20); the action size for the identity decoder
  n_synergies: int = 3
  # each task's own synergies beside the shared ones (0: none): task n's head also picks k
  # activations of k directions that only task n acts through, a = D(z) + W_n z_own, started
  # from what task n's own reward prior holds outside the shared start (priors.own); a task
  # acts in b + k dimensions. The task's own, so they learn beside a frozen decoder too
  own_synergies: int = 0
  decoder: str = "linear"  # linear (a b x 20 matrix) | mlp | identity (full-action PPO)
  decoder_bias: bool = True  # linear decoder: a = W z + c rather than W z
  freeze_decoder: bool = False  # decoder parameters outside the optimiser
  # the start of a linear decoder: random (the paper's), or a prior, the same subspace for
  # every seed, into which each seed's random decoder is turned (priors.py): objects,
  # the actions that move the tasks' objects most, pooled; reward, the actions that change
  # what each task rewards, each task its share of the directions in turn; auto: reward for
  # a linear decoder learned from scratch, random for any other (the config holds the start
  # it resolved to, so a run's config.json names it; decoder_from there where the decoder
  # is read from decoder_from; `replace` resolves auto again for the decoder it is given)
  decoder_init: str = "auto"
  # the initial decoder: a run directory (its latest checkpoint's decoder) or a synergy file
  # written by discosyn_jax.synergies.fitting (PCA / autoencoder); "" starts from a random one
  decoder_from: str = ""
  # False: a = the decoder's mean during training too (the sequential baselines' fixed spaces)
  decoder_noise: bool = True
  # the decoder reads tanh(z): synergy activations bounded to [-1, 1], so that the heads
  # cannot make up for any decoder by driving z far out (with z free a random decoder did as
  # well, docs/notes/2026-11-29-a-decoder-does-not-learn.md); the identity decoder (full-action PPO) reads z as it is
  squash_z: bool = True
  # what the discriminator q(.|a) reads back from the action: z, the head's sample (the
  # paper's), or activation, what the decoder read (tanh z where z is bounded: a z deep in
  # tanh's saturation cannot be read back, and its bonus pays the heads for narrowing z)
  discriminator_target: str = "z"
  # a learned posture per task added to the decoder's mean, a = W z + c + c_n: the shared
  # synergies then span each task's motions around its own posture rather than the
  # differences between the tasks' postures; the postures are the tasks' own, so they learn
  # beside a frozen decoder too (not for the identity decoder, whose heads choose every action)
  task_posture: bool = False
  # AdamW weight decay of the decoder's weights, a tie-breaker between adequate synergy
  # spaces: among the decoders that serve the tasks equally well, the smallest
  # (0: the paper's update)
  decoder_weight_decay: float = 0.0
  # the decay falls linearly to nothing over this many train steps, then stays off (0:
  # constant): the tie is broken by the decay integrated early, and a decay still on at the
  # end costs the decoder its reach (docs/notes/2026-12-02-a-planted-test-bed.md); a resumed run keeps its schedule
  decoder_weight_decay_steps: int = 0
  # -- a residual beside the synergies (discosyn_jax/agent/residual.py) --
  # the cap of the residual's weight rho: each task's head also picks a full-action residual
  # r (its mean bounded to [-1, 1]) and the action is the synergies' plus rho r, for motion
  # outside the synergy space; 0-1 (0: no residual, no parameters, no draws)
  residual: float = 0.0
  # rho rises linearly from 0 to its cap over this share of the run's `steps` (0-1), so that
  # the residual does not cost the synergies' start (0: the cap from the first step); a share,
  # so that one schedule means the same at every scale
  residual_ramp: float = 0.0
  # rho is held at 0 for this share of the run's `steps` before its ramp (0: the ramp starts
  # at once)
  residual_start: float = 0.0
  # initial std of the residual's own noise (small: the residual explores with the
  # decoder's noise, integrated over r)
  init_residual_std: float = 0.05
  # -- the extended reward, paper Eq. 2: alpha1 H(pi(z|s,n)) + alpha2 log q(z|a) + alpha3 H(p(a|z)) --
  alpha1: float = 1e-3  # weight of the entropy bonus H(pi(z|s,n)) in the loss
  # weight of the discriminator reward log q(z|a), added to the reward of every control step
  alpha2: float = 1e-2
  alpha3: float = 1e-3  # weight of the decoder entropy bonus H(p(a|z)) in the loss
  # each task's bonus alpha2 log q capped, per rollout, at the spread of what the task itself
  # pays: scaled by min(1, std(reward) / std(bonus)), so that the bonus cannot outweigh the
  # task's own reward, and a task that pays nothing is not steered by the bonus alone
  # (which pays its exploration to narrow); off: the paper's constant alpha2
  bonus_cap: bool = False
  # -- networks --
  policy_hidden: tuple[int, ...] = (128, 128)
  value_hidden: tuple[int, ...] = (128, 128)
  decoder_hidden: tuple[int, ...] = (128, 128)  # mlp decoder only
  discriminator_hidden: tuple[int, ...] = (128, 128)
  init_z_std: float = 1.0  # initial std of pi(z|s,n)
  # a floor on each head's z std, held until its task first pays a training rollout (a
  # reward of at least +0.01 at some step): the discriminator's bonus cannot narrow a head
  # before its task has paid it anything; a dense task is paid at once (0: no floor)
  z_std_floor: float = 0.0
  init_action_std: float = 0.3  # initial std of p(a|z)
  # each task's own std of p(a|z), the action's noise around the shared decoder's mean, in
  # place of the one std all tasks share: the tasks that pay narrow their own noise, not
  # that of a task not yet found; a task's own, so it learns beside a frozen decoder too
  # (needs the decoder's noise; not for the identity decoder, whose heads own theirs)
  task_noise: bool = False
  # -- PPO --
  num_envs: int = 64  # parallel envs per task
  unroll_length: int = 20  # control steps every env takes per train step
  num_minibatches: int = 4  # minibatches per PPO epoch
  update_epochs: int = 4  # PPO epochs over each train step's samples
  # Adam learning rate of the policy, value and decoder networks
  learning_rate: float = 3e-4
  discriminator_learning_rate: float = 3e-4
  discount: float = 0.97
  gae_lambda: float = 0.95
  clip_epsilon: float = 0.2
  value_coef: float = 0.5
  max_grad_norm: float = 1.0
  reward_scaling: float = 1.0
  normalize_observations: bool = True
  # -- the run --
  # train steps in all (a resumed run counts those done); one train step is
  # len(tasks) x num_envs x unroll_length env (control) steps
  steps: int = 100
  seed: int = 0  # seed of the initial networks, initial states and training noise
  # physics backend: native (MuJoCo C, CPU), mjx, or auto (native on a CPU, mjx on an
  # accelerator)
  backend: str = "auto"
  # the tasks' physics: fast (each task's cheapest faithful setting) or reference (4 ms x 10
  # substeps, the runs before 2026-12-02); docs/BENCHMARKS.md, "Physics settings"
  physics: str = "fast"
  # episodes restart from num_envs initial states per task made at init, drawn at random,
  # not from a fresh reset: MJX's train step then compiles no mjx.forward (wrappers.py)
  reset_pool: bool = False
  # train steps between deterministic evaluations (0: only at the end)
  eval_every: int = 20
  eval_envs: int = 32  # episodes per task in an evaluation
  # episodes per task of the closing evaluation that ends every run, kept beside the curve
  # (closing.json): a final figure that one evaluation of eval_envs episodes cannot swing (0:
  # none)
  closing_episodes: int = 128
  checkpoint_every: int = 50  # train steps between checkpoints (0: only the final one)
  keep_checkpoints: int = 3  # periodic checkpoints kept besides `final`

  def __post_init__(self):
    # the config says the start it runs; one made with auto remembers it (not a field: two
    # configs that run the same are equal), so that `replace` gives another decoder its own
    object.__setattr__(self, "_auto_start", self.decoder_init == "auto")
    if self.decoder_init == "auto":
      learned_from_scratch = (self.decoder in decoders.KINDS and self.kind.linear
                              and not self.decoder_from and not self.freeze_decoder)
      object.__setattr__(self, "decoder_init", "reward" if learned_from_scratch else "random")

  @property
  def residual_start_step(self) -> int:
    """The train step at which the residual's ramp begins (residual_start of `steps`)."""
    return round(self.residual_start * self.steps)

  @property
  def residual_ramp_step_count(self) -> int:
    """The train steps the residual's ramp lasts (residual_ramp of `steps`)."""
    return round(self.residual_ramp * self.steps)

  @property
  def kind(self) -> decoders.DecoderKind:
    """What the decoder is (discosyn_jax/decoders.py)."""
    return decoders.kind(self.decoder)

  @property
  def env_steps_per_train_step(self) -> int:
    return len(self.tasks) * self.num_envs * self.unroll_length

  def validate(self) -> "TrainConfig":
    """Raise BadInput naming the first impossible setting; return self."""
    checks.fields(self)  # types first: a string or NaN fails here, not in the checks below
    checks.seed(self.seed)
    if not self.tasks:
      raise BadInput("no tasks given")
    if len(set(self.tasks)) != len(self.tasks):
      raise BadInput(f"a task is listed twice: {', '.join(self.tasks)}")
    if not self.hand:
      raise BadInput("no hand given")
    kind = self.kind  # an unknown name fails here
    if kind.full_action:
      if self.alpha2 or self.alpha3:
        raise BadInput("the identity decoder (full-action PPO) has no discriminator or decoder "
                       "noise: set alpha2 = alpha3 = 0")
    elif not 1 <= self.n_synergies <= 20:
      raise BadInput(f"the synergy count must be between 1 and 20, not {self.n_synergies}")
    if self.own_synergies:
      if kind.full_action:
        raise BadInput("the identity decoder (full-action PPO) has no room for a task's own "
                       "synergies: its heads choose every action; set own_synergies = 0")
      if not 1 <= self.n_synergies + self.own_synergies <= 20:
        raise BadInput(f"shared plus own synergies must be at most 20, not "
                       f"{self.n_synergies} + {self.own_synergies}")
    if self.task_posture and kind.full_action:
      raise BadInput("the identity decoder (full-action PPO) has no room for a task posture: "
                     "its heads choose every action; set task_posture = false")
    if self.discriminator_target not in DISCRIMINATOR_TARGETS:
      raise BadInput(f"unknown discriminator_target {self.discriminator_target!r}; known: "
                     f"{', '.join(DISCRIMINATOR_TARGETS)}")
    if self.decoder_init not in DECODER_INITS:
      raise BadInput(f"unknown decoder_init {self.decoder_init!r}; known: {', '.join(DECODER_INITS)}")
    if self.decoder_init in PRIORS and (not kind.linear or self.decoder_from):
      raise BadInput(f"the {self.decoder_init} prior starts a linear decoder of its own: "
                     "decoder linear, no decoder_from")
    if self.decoder_from and kind.full_action:
      raise BadInput("the identity decoder (full-action PPO) cannot take a decoder_from")
    if self.freeze_decoder and (self.decoder_weight_decay or self.decoder_weight_decay_steps):
      raise BadInput("a frozen decoder is not decayed: set decoder_weight_decay = 0 and "
                     "decoder_weight_decay_steps = 0")
    if self.decoder_weight_decay_steps and not self.decoder_weight_decay:
      raise BadInput("decoder_weight_decay_steps anneals a decoder_weight_decay: set one")
    if self.bonus_cap and kind.full_action:
      raise BadInput("the identity decoder (full-action PPO) has no discriminator bonus to cap: "
                     "set bonus_cap = false")
    if self.task_noise and (kind.full_action or not self.decoder_noise):
      raise BadInput("task_noise gives each task its own decoder noise: it needs a decoder "
                     "with noise (not identity, decoder_noise true)")
    if not self.decoder_noise and self.alpha3:
      raise BadInput("a noiseless decoder (decoder_noise false) has no entropy: set alpha3 = 0")
    if self.physics not in PHYSICS:
      raise BadInput(f"unknown physics {self.physics!r}; known: {', '.join(PHYSICS)}")
    positive = ("num_envs", "unroll_length", "num_minibatches", "update_epochs", "steps",
                "eval_envs", "keep_checkpoints")
    for name in positive:
      if getattr(self, name) < 1:
        raise BadInput(f"{name} must be at least 1, not {getattr(self, name)}")
    if self.steps > MAX_STEPS:
      raise BadInput(f"steps must be at most {MAX_STEPS}, not {self.steps}")
    for name in ("own_synergies", "eval_every", "checkpoint_every", "alpha1", "alpha2", "alpha3", "value_coef",
                 "decoder_weight_decay", "decoder_weight_decay_steps", "residual_ramp",
                 "residual_start", "closing_episodes", "z_std_floor"):
      if getattr(self, name) < 0:
        raise BadInput(f"{name} must not be negative, not {getattr(self, name)}")
    for name in ("policy_hidden", "value_hidden", "decoder_hidden", "discriminator_hidden"):
      if any(width < 1 for width in getattr(self, name)):
        raise BadInput(f"the layer widths of {name} must be at least 1, not {getattr(self, name)}")
    samples = self.num_envs * self.unroll_length
    if samples % self.num_minibatches:
      raise BadInput(f"num_envs x unroll_length = {samples} does not split into "
                     f"{self.num_minibatches} minibatches")
    if not 0 < self.discount <= 1 or not 0 <= self.gae_lambda <= 1:
      raise BadInput("discount must be in (0, 1] and gae_lambda in [0, 1]")
    for name in ("init_z_std", "init_action_std", "init_residual_std", "learning_rate",
                 "discriminator_learning_rate", "clip_epsilon", "max_grad_norm", "reward_scaling"):
      if getattr(self, name) <= 0:
        raise BadInput(f"{name} must be positive, not {getattr(self, name)}")
    self._check_residual()
    return self

  def _check_residual(self) -> None:
    if not 0 <= self.residual <= 1:
      raise BadInput(f"residual (the cap of the residual's weight) must be between 0 and 1, "
                     f"not {self.residual}")
    if self.residual_start + self.residual_ramp > 1:
      raise BadInput(f"residual_start + residual_ramp are shares of the run: their sum must be "
                     f"at most 1, not {self.residual_start + self.residual_ramp:g}")
    if not self.residual:
      if self.residual_ramp or self.residual_start:
        raise BadInput("residual_ramp and residual_start schedule a residual: set residual")
    elif self.kind.full_action:
      raise BadInput("the identity decoder (full-action PPO) has no room for a residual: its "
                     "heads choose every action; set residual = 0")
    elif not self.decoder_noise:
      raise BadInput("a residual explores with the decoder's noise: a noiseless decoder "
                     "(decoder_noise false) leaves it none; set residual = 0")

  def to_dict(self) -> dict[str, Any]:
    return dataclasses.asdict(self)

  @classmethod
  def from_dict(cls, values: dict[str, Any]) -> "TrainConfig":
    fields = {f.name: f for f in dataclasses.fields(cls)}
    values = renamed(values)
    unknown = sorted(set(values) - set(fields))
    if unknown:
      raise BadInput(f"unknown config field(s): {', '.join(unknown)}")
    missing = [name for name in fields if name not in values]
    if missing:
      raise BadInput(f"missing config field(s): {', '.join(missing)}")
    init = values["decoder_init"]
    if init == GIVEN_START:
      if not values["decoder_from"]:
        raise BadInput(f"decoder_init is {GIVEN_START}, but no decoder_from is given")
      init = "random"
    values = {**values, "decoder_init": OLD_STARTS.get(init, init)}
    # JSON has no tuples
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})

  def replace(self, **changes) -> "TrainConfig":
    """A copy with `changes`; a start resolved from auto is resolved again (a frozen or mlp
    decoder starts at random), one given stays."""
    if self._auto_start and "decoder_init" not in changes:
      changes["decoder_init"] = "auto"
    return dataclasses.replace(self, **changes)


def renamed(values: dict[str, Any]) -> dict[str, Any]:
  """Config fields under their names of today (RENAMED): an older residual schedule in train
  steps becomes its share of the run's `steps`."""
  values = dict(values)
  for old, new in RENAMED.items():
    if old in values and new not in values:
      steps = values.get("steps")
      count = values.pop(old)
      if not isinstance(steps, int) or steps < 1 or not isinstance(count, int):
        raise BadInput(f"{old} = {count!r} cannot become a share of steps = {steps!r}")
      values[new] = count / steps
  return values


def with_added(values: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
  """(the fields of an older release's config under today's names, with those added since
  (ADDED) at the values that release ran; the names of the added)."""
  values = renamed(values)
  added = [k for k in ADDED if k not in values]
  return {**values, **{k: ADDED[k] for k in added}}, added


def save(config: TrainConfig, path) -> None:
  """Write `config` to the file at `path`; a decoder read from decoder_from is said to start
  there (GIVEN_START), not at "random"."""
  values = config.validate().to_dict()
  if values["decoder_from"] and values["decoder_init"] == "random":
    values["decoder_init"] = GIVEN_START
  atomic.write_text(path, json.dumps(values, indent=1))


def load(path) -> TrainConfig:
  """The checked config in the file at `path`; BadInput naming the file and the field."""
  try:
    with open(path) as f:
      values = json.load(f)
  except json.JSONDecodeError as err:
    raise BadInput(f"malformed config file {path}: {err}") from None
  if not isinstance(values, dict):
    raise BadInput(f"malformed config file {path}: not a JSON object")
  try:
    return TrainConfig.from_dict(values).validate()
  except (TypeError, ValueError) as err:
    older = sorted(set(ADDED) - set(values) - {RENAMED[k] for k in values if k in RENAMED})
    hint = (f"; a run of an older release: `discosyn upgrade {pathlib.Path(path).parent}` adds "
            f"{', '.join(f'{k} = {json.dumps(ADDED[k])}' for k in older)}, as it ran"
            if older and "missing" in str(err) else "")
    raise BadInput(f"config file {path}: {err}{hint}") from None


def upgrade(path) -> list[str]:
  """Write the fields added since an older release (ADDED) into the config file at
  `path`, with the values that release ran; return their names. Anything else missing or
  wrong is still refused by load()."""
  try:
    values = json.loads(pathlib.Path(path).read_text())
  except json.JSONDecodeError as err:
    raise BadInput(f"malformed config file {path}: {err}") from None
  if not isinstance(values, dict):
    raise BadInput(f"malformed config file {path}: not a JSON object")
  renames = [old for old in RENAMED if old in values]
  upgraded, added = with_added(values)
  try:  # the rest must be whole already
    TrainConfig.from_dict(upgraded).validate()
  except (TypeError, ValueError) as err:
    raise BadInput(f"config file {path}: {err}") from None
  if added or renames:  # in the order of today's fields, as a new run writes them
    order = [f.name for f in dataclasses.fields(TrainConfig)]
    upgraded = {k: upgraded[k] for k in sorted(upgraded, key=order.index)}
    atomic.write_text(path, json.dumps(upgraded, indent=1))
  return added + [f"{RENAMED[old]} (was {old})" for old in renames]


def mismatches(saved: TrainConfig, requested: TrainConfig) -> list[str]:
  """Fields in which `requested` cannot continue the run that `saved` describes."""
  out = [f"{name} is {getattr(saved, name)!r} in the run but {getattr(requested, name)!r} here"
         for name in saved.to_dict()
         if name not in RESUMABLE and getattr(saved, name) != getattr(requested, name)]
  scheduled = saved.residual and (saved.residual_ramp or saved.residual_start)
  if scheduled and saved.steps != requested.steps:  # the schedule is a share of steps
    out.append(f"steps is {saved.steps} in the run but {requested.steps} here, and its residual's "
               "schedule is a share of steps")
  return out


def same_run(a: TrainConfig, b: TrainConfig) -> bool:
  """Whether two configs train the same run (they may differ in AFTER_THE_RUN alone)."""
  strip = lambda c: {k: v for k, v in c.to_dict().items() if k not in AFTER_THE_RUN}
  return strip(a) == strip(b)


@functools.cache
def field_docs() -> dict[str, str]:
  """Each TrainConfig field's documentation: its comment lines in the class (those right
  above the field, back to a "# --" group heading, and the one beside it), read from the
  source, so that the command line's help and the code say one thing."""
  lines = inspect.getsource(TrainConfig).splitlines()
  names = {f.name for f in dataclasses.fields(TrainConfig)}
  docs, above = {}, []
  for line in lines:
    text = line.strip()
    if text.startswith("#"):
      above = [] if text.startswith("# --") else above + [text[1:].strip()]
      continue
    name = text.split(":", 1)[0]
    if name in names:
      beside = [tok.string[1:].strip() for tok in tokenize.generate_tokens(io.StringIO(text).readline)
                if tok.type == tokenize.COMMENT]
      docs[name] = " ".join(above + beside)
    above = []
  return docs
