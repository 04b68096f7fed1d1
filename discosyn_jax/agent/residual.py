"""A residual beside the synergies: each task's head also picks a full-action correction r,
added to the shared decoder's action with a weight rho(t) that a schedule ramps in and caps
(TrainConfig.residual, residual_ramp, residual_start: shares of the run's steps). In the spirit of SAR
(MyoSuite, RSS 2023: phi * synergy action + (1 - phi) * raw action) and DynSyn (ICML 2024:
state-dependent per-actuator corrections whose weight ramps up and is capped).

  r ~ pi(r | s, n) = N(tanh(m_n(s)), sigma_r)   a residual head per task (networks.py); the
                                                 mean is bounded, so the cap bounds what the
                                                 residual can carry: |rho tanh m| <= rho per
                                                 actuator. sigma_r: its own small learned
                                                 std, from init_residual_std
  a = D(z) [+ c_n] + rho(t) r + sigma_phi eps    the decoder's noise as without the residual

The log-probability PPO uses integrates r out, exactly (a sum of independent Gaussians):

  log pi(z, a | s, n) = log pi(z | s, n) + log N(a; D(z) [+ c_n] + rho tanh m_n(s),
                                                 sigma_phi^2 + rho^2 sigma_r^2)

rather than scoring r's own draw (log pi(r|s,n) + log p(a|z,r), r kept in the samples). Both
are likelihoods of the same actions; the marginal's gradient for the residual's mean comes
from the whole action noise, the draw's only from rho sigma_r eps_r, 20x smaller than the
decoder's noise at the defaults (0.3 x 0.05 against 0.3). The residual thus explores with
the noise the decoder has anyway and costs the start no exploration of its own; its own
noise only widens the action's by rho^2 sigma_r^2. On a planted task a frozen span cannot
finish, the draw's form learned nothing in 300 train steps where the marginal's reached a
return of 9.0-9.5 of 10 (docs/notes/2026-12-05-c-residual-planted.md). It needs the decoder's noise
(decoder_noise on); rho = 0 leaves the residual's parameters without a gradient: held at 0
it does not drift.

What the extended reward (paper, Eq. 2) means with the residual:
  alpha2 log q(z | a)  q still reads z back from the whole action, the residual's part
                       included: its bonus pays the heads for keeping the synergies
                       identifiable, a pressure against a residual that takes over what z
                       would carry
  alpha3 H(p(a | z))   the decoder's own noise sigma_phi, as before
  alpha1 H(pi(z|s,n))  z's alone: the residual's entropy is in no bonus. Its noise is meant
                       to stay small (wide full-action noise from the start diluted the
                       synergies' exploration, docs/notes/2026-12-05-c-residual-planted.md); PPO alone sets it
With residual = 0 none of this exists: no parameters, no draws, today's computation.
"""

from __future__ import annotations

import jax.numpy as jnp

from discosyn_jax.config import TrainConfig


def rho(config: TrainConfig, step) -> jnp.ndarray:
  """The residual's weight at `step` (train steps done, an int or a traced int32): 0 for the
  first residual_start of the run's steps, then rising linearly to the cap `residual` over
  residual_ramp of them (at once when 0), then held there. The shares are rounded to whole
  train steps (TrainConfig.residual_start_step), so a schedule in steps is met exactly."""
  since = jnp.asarray(step, jnp.float32) - config.residual_start_step
  if config.residual_ramp_step_count:
    progress = jnp.clip(since / config.residual_ramp_step_count, 0.0, 1.0)
  else:
    progress = (since >= 0).astype(jnp.float32)
  return config.residual * progress
