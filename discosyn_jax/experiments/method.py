"""What a run is, as a value: a `Method` (family, synergies, decoder, start, decay, control,
residual, reuse) whose `.name` is the row name the records carry ('PPO', 'PCA4',
'DiscoSyn3-L-reward', 'Random3-L-zfree-res0.3r150', 'DiscoSyn3-L-reward frozen'), read back
by `Method.parse`; `Method.of(config)` names what a config runs; `rank` is the order of the
report's rows. The planner builds Methods, the report groups and orders runs by them.

A name, part by part: the family and its number of synergies ('DiscoSyn3'), with each
task's own synergies beside the shared ones after a plus ('DiscoSyn6+3': six shared, three
of each task's own, so a task acts in nine); the decoder
('-L' linear, '-NL' mlp; none for PPO and the fitted PCA / AE); '-matched' for the random
decoder that copies a learned run's update (the parts after it are that run's); the
decoder's start where not random ('-reward', '-objects'); its weight decay ('-wd8a200':
8, falling to nothing over 200 train steps); '-zfree' where the heads' z is unbounded; a
study's own label parts ('-alpha3=0.1'); a floor on the heads' z std until paid
('-zfloor0.7'), each task's own decoder noise ('-tasknoise') and its bonus capped at what it
pays ('-bonuscap'); a residual beside the synergies ('-res0.3r150s400':
its cap, ramp and start in the run's train steps); and ' frozen' for that space frozen and
used on other tasks, or ' tuned' for it learned on there (a run's decoder_from, not frozen),
with the residual it acts with there ('... frozen-res0.3r150')."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

from discosyn_jax import decoders
from discosyn_jax.checks import BadInput
from discosyn_jax.config import GIVEN_START, OLD_STARTS
from discosyn_jax.experiments.presets import DECAY  # the decayed update's row (rank)

FAMILIES = ("PPO", "PCA", "AE", "DiscoSyn", "Random", "Prior")
STARTS = ("reward", "objects")  # a decoder's start as the name says it; random says nothing
CONTROLS = ("matched", "zfree")
REUSES = ("frozen", "tuned")  # how a space learned on some tasks is used on others
# a config's switches a name carries as a part of its own: each task's own decoder noise,
# each task's bonus capped at what it pays (Method.of writes them, rows.config_for reads them)
SWITCH_TAGS = {"task_noise": "tasknoise", "bonus_cap": "bonuscap"}
FLOOR_TAG = "zfloor"  # a floor on the heads' z std until paid: 'zfloor0.7'


@dataclasses.dataclass(frozen=True)
class Residual:
  """A residual beside the synergies (agent/residual.py): its cap, and its ramp and start in
  the run's train steps (0: none)."""
  cap: float
  ramp: int = 0
  start: int = 0

  @property
  def name(self) -> str:
    return f"-res{self.cap:g}" + (f"r{self.ramp}" if self.ramp else "") + (
        f"s{self.start}" if self.start else "")

  @classmethod
  def of(cls, source) -> "Residual | None":
    """The residual a config (or a dict of its fields) runs with, None without one."""
    get = _getter(source)
    cap = get("residual", 0.0) or 0.0
    if not cap:
      return None
    steps = get("steps", 0) or 0
    return cls(cap, round((get("residual_ramp", 0.0) or 0.0) * steps),
               round((get("residual_start", 0.0) or 0.0) * steps))


_RESIDUAL = re.compile(r"res(?P<cap>\d+(?:\.\d+)?)(?:r(?P<ramp>\d+))?(?:s(?P<start>\d+))?")
_DECAY = re.compile(r"wd(?P<decay>\d+(?:\.\d+)?)(?:a(?P<steps>\d+))?")


def _name_pattern() -> re.Pattern:
  """A method's name; its decoder part is any registered kind's letter (decoders.py)."""
  letters = sorted((k.letter for k in decoders.learned()), key=len, reverse=True)
  return re.compile(r"(?P<family>" + "|".join(FAMILIES) + r")(?P<b>\d*)(?:\+(?P<own>\d+))?"
                    r"(?:-(?P<decoder>" + "|".join(map(re.escape, letters)) + r"))?"
                    r"(?P<parts>(?:-[^ ]+)?)(?: (?P<reuse>" + "|".join(REUSES) + r")(?P<acting>-\S+)?)?")


@dataclasses.dataclass(frozen=True)
class Method:
  family: str
  synergies: int = 0  # b; 0 for PPO
  decoder: str = ""  # its kind's letter ("L", "NL"); "" for PPO and a fitted space
  control: str = ""  # "matched" or "zfree" (CONTROLS), "" for none
  start: str = ""  # the decoder's start (STARTS); "" for random
  decay: float = 0.0  # the decoder's weight decay, and the train steps it falls over
  decay_steps: int = 0
  tag: tuple[str, ...] = ()  # a study's own label parts
  residual: Residual | None = None
  reuse: str = ""  # this space used on other tasks (REUSES): frozen, or tuned (learned on)
  acting_residual: Residual | None = None  # the residual the reused space acts with there
  own: int = 0  # each task's own synergies beside the b shared (config own_synergies)

  def __post_init__(self):
    if self.family not in FAMILIES:
      raise BadInput(f"unknown method family {self.family!r}; families: {', '.join(FAMILIES)}")
    if self.reuse not in ("", *REUSES):
      raise BadInput(f"unknown reuse {self.reuse!r}; one of: {', '.join(REUSES)}")

  @property
  def name(self) -> str:
    name = self.family + (str(self.synergies) if self.synergies else "")
    name += f"+{self.own}" if self.own else ""
    name += f"-{self.decoder}" if self.decoder else ""
    name += "-matched" if self.control == "matched" else ""
    name += f"-{self.start}" if self.start else ""
    if self.decay:
      name += f"-wd{self.decay:g}" + (f"a{self.decay_steps}" if self.decay_steps else "")
    name += "-zfree" if self.control == "zfree" else ""
    name += "".join(f"-{part}" for part in self.tag)
    name += self.residual.name if self.residual else ""
    if self.reuse:
      name += f" {self.reuse}" + (self.acting_residual.name if self.acting_residual else "")
    return name

  def __str__(self) -> str:
    return self.name

  def __lt__(self, other: "Method") -> bool:  # runs sorted by name where ranks tie
    return self.name < other.name

  def replace(self, **changes) -> "Method":
    return dataclasses.replace(self, **changes)

  @classmethod
  def parse(cls, name: str) -> "Method":
    """The Method a name stands for; a name this release would not write is refused."""
    match = _name_pattern().fullmatch(name)
    if not match:
      raise BadInput(f"{name!r} is not a method's name (e.g. PPO, PCA4, DiscoSyn3-L-reward, "
                     "Random3-L-zfree, DiscoSyn3-L-reward frozen)")
    fields: dict[str, Any] = dict(family=match["family"], synergies=int(match["b"] or 0),
                                  own=int(match["own"] or 0),
                                  decoder=match["decoder"] or "", reuse=match["reuse"] or "")
    tag = []
    for part in match["parts"].split("-")[1:]:
      residual, decay = _RESIDUAL.fullmatch(part), _DECAY.fullmatch(part)
      if part in CONTROLS:
        fields["control"] = part
      elif part in STARTS:
        fields["start"] = part
      elif decay:
        fields.update(decay=float(decay["decay"]), decay_steps=int(decay["steps"] or 0))
      elif residual:
        fields["residual"] = _residual(residual)
      else:
        tag.append(part)
    if match["acting"]:
      acting = _RESIDUAL.fullmatch(match["acting"][1:])
      if not acting:
        raise BadInput(f"{name!r}: a method used on other tasks acts with a residual ('-res0.3r150'), "
                       f"not {match['acting'][1:]!r}")
      fields["acting_residual"] = _residual(acting)
    method = cls(**fields, tag=tuple(tag))
    if method.name != name:  # parts out of their order, or a residual not last
      raise BadInput(f"{name!r} is not a method's name as written: its parts in order "
                     f"read {method.name!r}")
    return method

  @classmethod
  def of(cls, source) -> "Method":
    """What a config runs (or a synergy file's meta says it holds): PPO for the full action
    space; a fitted space by its method ('PCA4'); else a decoder, frozen at its own start
    (Random, Prior) or learned (DiscoSyn); a random one frozen with z free is `-zfree`.
    `-matched` and ` frozen` are the planner's to add: they name where a config's decoder_from
    came from, which the config does not say."""
    get = _getter(source)
    floor = get("z_std_floor", 0.0) or 0.0  # the heads held open until paid
    tag = (f"{FLOOR_TAG}{floor:g}",) if floor else ()
    tag += tuple(part for field, part in SWITCH_TAGS.items() if get(field))
    kind = decoders.kind(get("decoder"))
    if kind.full_action:
      return cls("PPO", tag=tag)
    if get("method"):  # a fitted space: PCA, AE
      return cls(get("method"), get("n_synergies"))
    init = get("decoder_init", "random") or "random"
    init = "random" if init == GIVEN_START else OLD_STARTS.get(init, init)
    family, control = "DiscoSyn", ""
    if get("freeze_decoder") and not get("decoder_from"):
      family = "Random" if init == "random" else "Prior"
      # a random decoder frozen with the heads' z unbounded: the strongest control
      control = "zfree" if family == "Random" and not get("squash_z") else ""
    decay = 0.0 if get("freeze_decoder") else (get("decoder_weight_decay", 0.0) or 0.0)
    return cls(family, get("n_synergies"), kind.letter, control, own=get("own_synergies", 0) or 0,
               start="" if init == "random" else init, decay=decay,
               decay_steps=(get("decoder_weight_decay_steps", 0) or 0) if decay else 0,
               tag=tag, residual=Residual.of(source))

  @property
  def plain(self) -> Method:
    """The method without its residual, tag or freezing: the row it belongs to."""
    return self.replace(tag=(), residual=None, reuse="", acting_residual=None)

  def rank(self) -> tuple:
    """The report's order: PPO, the fitted spaces (PCA, AE by size), then per number of
    synergies each linear DiscoSyn start above its controls (the reward prior's, the
    objects prior's, the paper's random start, the preset decay's update), the random
    decoder (z bounded, z free), the mlp rows; every other method after, by name."""
    if self != self.plain:
      return (9, self.name)
    if self.family == "PPO":
      return (0,)
    if self.family in ("PCA", "AE") and not self.decoder:
      return (1, self.synergies, FAMILIES.index(self.family))
    place = _ROWS.get((self.family, self.decoder, self.control,
                       (self.start, self.decay, self.decay_steps)))
    return (2, self.synergies, *place, self.own) if place else (9, self.name)


def _rows() -> dict[tuple, tuple[int, int]]:
  """(family, decoder, control, (start, decay, decay steps)) -> its place in its b's group."""
  paper = ("", 0.0, 0)  # the paper's update: a random start, no decay
  updates = [(start, 0.0, 0) for start in STARTS] + [
      paper, ("", DECAY["decoder_weight_decay"], DECAY["decoder_weight_decay_steps"])]
  linear, mlp = decoders.LINEAR.letter, decoders.MLP.letter
  rows = {}
  for slot, each in enumerate(updates):
    rows[("DiscoSyn", linear, "", each)] = (slot, 0)
    if each[0]:  # a prior's start frozen
      rows[("Prior", linear, "", each)] = (slot, 1)
    rows[("Random", linear, "matched", each)] = (slot, 2)
  rows.update({("Random", linear, "", paper): (4, 0), ("Random", linear, "zfree", paper): (4, 1),
               ("DiscoSyn", mlp, "", paper): (5, 0), ("Random", mlp, "", paper): (5, 1),
               ("Random", mlp, "zfree", paper): (5, 2)})
  return rows


_ROWS = _rows()


def _residual(match: re.Match) -> Residual:
  return Residual(float(match["cap"]), int(match["ramp"] or 0), int(match["start"] or 0))


def _getter(source):
  return source.get if isinstance(source, dict) else lambda k, d=None: getattr(source, k, d)
