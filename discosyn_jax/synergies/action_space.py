"""Synergies as an action space for any JAX RL library: `synergy_env(env, synergies)` wraps a
Brax env so that its action is what the synergy decoder reads and the hand gets the decoder's
mean action.

The wrapped env's action u has b entries. For synergies learned with z bounded (the default)
the decoder read tanh(z) in training, so u is that activation, in [-1, 1] (clipped there):
the range Brax's PPO and most continuous-control libraries act in. For synergies learned with
z free, u is z itself. The hand gets D(u), the decoder's mean (no decoder noise: the RL
library's own exploration is in u), which the env clips to [-1, 1] and maps onto each
actuator's ctrlrange as it does any action.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env, State, Wrapper

from discosyn_jax.agent import networks
from discosyn_jax.synergies import fitting
from discosyn_jax.synergies.artefact import Synergies, SynergyFileError


def env_actuators(env: Env) -> tuple[str, ...] | None:
  """The actuators of a hand env in action order (None for an env without a MuJoCo hand)."""
  from discosyn_jax.env import hands

  inner = env
  while not hasattr(inner, "mj_model") and hasattr(inner, "env"):
    inner = inner.env
  model = getattr(inner, "mj_model", None)
  return None if model is None else tuple(hands.actuator_names(model))


class SynergyEnv(Wrapper):
  """A Brax env whose action is u (b entries) and whose hand gets the decoder's mean D(u)."""

  def __init__(self, env: Env, synergies: Synergies):
    super().__init__(env)
    actuators = env_actuators(env)
    if actuators is not None:
      synergies.check_hand(actuators, f"the env's hand ({_hand_name(env)})")
    elif env.action_size != synergies.action_size:
      raise SynergyFileError(f"{synergies.source} drives {synergies.action_size} actions, the "
                             f"env takes {env.action_size}")
    self.synergies = synergies
    # the decoder alone, reading u as it is: u is already what it read in training
    self._model = fitting._decoder_model({**synergies.meta, "squash_z": False}, synergies.params)
    self._params = {"params": {"synergy_decoder": jax.tree.map(jnp.asarray, synergies.params)}}

  @property
  def action_size(self) -> int:
    return self.synergies.b

  def action(self, u: jax.Array) -> jax.Array:
    """The hand's action for u: the decoder's mean at u (clipped to [-1, 1] where z was
    bounded in training)."""
    u = jnp.clip(u, -1.0, 1.0) if self.synergies.bounded else u
    mean, _ = self._model.apply(self._params, u, method=networks.DiscoSyn.decode)
    return mean

  def reset(self, rng: jax.Array) -> State:
    return self.env.reset(rng)

  def step(self, state: State, action: jax.Array) -> State:
    return self.env.step(state, self.action(action))


def _hand_name(env: Env) -> str:
  inner = env
  while not hasattr(inner, "hand") and hasattr(inner, "env"):
    inner = inner.env
  hand = getattr(inner, "hand", None)
  from discosyn_jax.env import hands

  return hands.label(hand.name) if hand is not None else "unknown"


def synergy_env(env: Env, synergies: Synergies | str) -> SynergyEnv:
  """`env` with the action space of `synergies` (a Synergies, a shipped name or a file)."""
  if not isinstance(synergies, Synergies):
    synergies = Synergies.load(synergies)
  return SynergyEnv(env, synergies)
