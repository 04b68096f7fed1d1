"""Is the synergy space being learned? The decoder's movement from where it started.

A decoder's synergy basis is a (20, b) matrix whose columns span the postures z reaches:
the linear decoder's W (a = W z + c), or an MLP decoder's Jacobian dD/dz at z = 0 (the
subspace its small-z postures span). Beside a reference decoder (its initial state) we
report
  decoder/change   |B - B0|_F / |B0|_F, the relative change of the basis
  decoder/cos_k    the cosines of the principal angles between the two column spaces,
                   largest first (1: the same subspace; a rotated subspace drops the last)
  decoder/cos_min  the smallest of them
A frozen decoder reports change 0 and cosines 1. Scaling or mixing the synergies inside their
subspace moves `change` but not the cosines: only a new subspace lowers them.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from discosyn_jax.networks import DiscoSyn


def synergy_basis(model: DiscoSyn, params) -> jax.Array:
  """The (action_size, b) basis of the decoder in `params` (the full param tree)."""
  if model.decoder == "linear":
    return params["params"]["synergy_decoder"]["synergies"]["kernel"].T
  mean = lambda z: model.apply(params, z[None], method=DiscoSyn.decode)[0][0]
  return jax.jacfwd(mean)(jnp.zeros((model.n_synergies,)))


def principal_cosines(a: jax.Array, b: jax.Array) -> jax.Array:
  """Cosines of the principal angles between the column spaces of a and b, descending."""
  qa, _ = jnp.linalg.qr(a)
  qb, _ = jnp.linalg.qr(b)
  return jnp.clip(jnp.linalg.svd(qa.T @ qb, compute_uv=False), 0.0, 1.0)


def decoder_drift(model: DiscoSyn, reference, params) -> dict[str, jax.Array]:
  """The decoder's movement in `params` from the one in `reference` (module docstring)."""
  b0, b1 = synergy_basis(model, reference), synergy_basis(model, params)
  cos = principal_cosines(b0, b1)
  out = {"decoder/change": jnp.linalg.norm(b1 - b0) / jnp.linalg.norm(b0),
         "decoder/cos_min": cos.min()}
  out.update({f"decoder/cos_{k}": c for k, c in enumerate(cos, 1)})
  return out
