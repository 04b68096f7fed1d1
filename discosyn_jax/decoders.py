"""Decoder kinds: what p(a | z) is, one value a kind. A config names its kind by a string
(`decoder`, as config.json writes it); everything that depends on the kind asks the
DecoderKind this module registers under that name, so adding a kind is one `register` call.

No JAX here (configs and presets import it): a kind's `build` gets the agent's building
blocks from the network that calls it (discosyn_jax/agent/networks.py)."""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

from discosyn_jax.checks import BadInput


@dataclasses.dataclass(frozen=True)
class DecoderKind:
  name: str  # as a config names it: TrainConfig.decoder
  # its part in a row's name ('DiscoSyn3-L'); "" for the full action, which has no synergies
  letter: str
  # the heads choose the whole action: no synergies, so no discriminator, no decoder noise and
  # nothing beside a decoder (own synergies, posture, residual, a task's noise, a start)
  full_action: bool = False
  # its synergies are a matrix's columns: a prior may start it, its basis is its kernel
  # (no Jacobian), its pictures include the matrix
  linear: bool = False
  # the config fields of its architecture a synergy file states beside the shared ones
  # (synergies/fitting.py ARCHITECTURE): a file of another kind leaves them out
  fields: tuple[str, ...] = ()
  # (network, blocks) -> the Flax module of p(a | z): `network` the DiscoSyn module (its
  # action_size, decoder_bias, decoder_hidden, init_action_std), `blocks` the module of the
  # agent's layers (LinearDecoder, GaussianHead, MLP); None for the full action
  build: Callable[[Any, Any], Any] | None = None

  def __post_init__(self):
    if self.full_action != (self.build is None):
      raise BadInput(f"decoder kind {self.name!r}: a kind builds a decoder unless the heads "
                     "choose the full action")


KINDS: dict[str, DecoderKind] = {}


def register(kind: DecoderKind) -> DecoderKind:
  """Add a kind; its name and its letter each name one kind."""
  if kind.name in KINDS:
    raise BadInput(f"a decoder kind named {kind.name!r} is registered already")
  if kind.letter and kind.letter in {k.letter for k in KINDS.values()}:
    raise BadInput(f"the letter {kind.letter!r} names a decoder kind already")
  KINDS[kind.name] = kind
  return kind


def unregister(name: str) -> None:
  """Remove a kind a user (or a test) added."""
  KINDS.pop(name, None)


def kind(name: str) -> DecoderKind:
  if name not in KINDS:
    raise BadInput(f"unknown decoder {name!r}; known: {', '.join(KINDS)}")
  return KINDS[name]


def by_letter(letter: str) -> DecoderKind:
  """The kind a row's name says ('L', 'NL')."""
  for each in KINDS.values():
    if each.letter == letter:
      return each
  raise BadInput(f"no decoder kind has the letter {letter!r}")


def learned() -> tuple[DecoderKind, ...]:
  """The kinds with synergies, in the order they were registered: the rows of the tables."""
  return tuple(k for k in KINDS.values() if not k.full_action)


LINEAR = register(DecoderKind(
    "linear", "L", linear=True, fields=("decoder_bias",),
    build=lambda net, blocks: blocks.LinearDecoder(net.action_size, net.decoder_bias,
                                                   net.init_action_std)))
MLP = register(DecoderKind(
    "mlp", "NL", fields=("decoder_hidden",),
    build=lambda net, blocks: blocks.GaussianHead(net.decoder_hidden, net.action_size,
                                                  net.init_action_std, out_scale=1.0)))
IDENTITY = register(DecoderKind("identity", "", full_action=True))  # full-action PPO
