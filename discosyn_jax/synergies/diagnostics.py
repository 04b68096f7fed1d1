"""Is the synergy space being learned? The decoder's movement from where it started.

A decoder's synergy basis is a (20, b) matrix whose columns span the postures z reaches:
the linear decoder's W (a = W z + c), or an MLP decoder's Jacobian dD/dz at z = 0 (the
subspace its small-z postures span). Beside a reference decoder (its initial state) we
report
  decoder/change   |B - B0|_F / |B0|_F, the relative change of the basis
  decoder/cos_k    the cosines of the principal angles between the two column spaces,
                   largest first (1: the same subspace; a rotated subspace drops the last)
  decoder/cos_min  the smallest of them
  decoder/overlap_start  the overlap (below) of the two subspaces
and, on tasks with a planted synergy span (discosyn_jax/tasks/planted.py),
  decoder/overlap_planted  the overlap of the decoder's subspace with the planted span.
A frozen decoder reports change 0 and cosines 1. Scaling or mixing the synergies inside their
subspace moves `change` but not the cosines: only a new subspace lowers them.

The overlap of two subspaces with orthonormal bases Qa (n, p), Qb (n, q) is
|Qa^T Qb|_F^2 / min(p, q), the mean squared principal-angle cosine: 1 when one holds the
other, 0 when they are orthogonal. Two random subspaces of R^n have max(p, q) / n on average
(`chance_overlap`): 0.15 for two 3-D subspaces of the 20 actions. Whether a task set
determines its synergy space is the overlap of the spaces learned from different seeds.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax.agent.networks import DiscoSyn


def synergy_basis(model: DiscoSyn, params) -> jax.Array:
  """The (action_size, b) basis of the decoder in `params` (the full param tree)."""
  if model.kind.linear:
    return params["params"]["synergy_decoder"]["synergies"]["kernel"].T
  mean = lambda z: model.apply(params, z[None], method=DiscoSyn.decode)[0][0]
  return jax.jacfwd(mean)(jnp.zeros((model.n_synergies,)))


def principal_cosines(a: jax.Array, b: jax.Array) -> jax.Array:
  """Cosines of the principal angles between the column spaces of a and b, descending."""
  qa, _ = jnp.linalg.qr(a)
  qb, _ = jnp.linalg.qr(b)
  return jnp.clip(jnp.linalg.svd(qa.T @ qb, compute_uv=False), 0.0, 1.0)


def overlap(a: jax.Array, b: jax.Array) -> jax.Array:
  """The overlap of the column spaces of a and b (module docstring), in [0, 1]."""
  cos = principal_cosines(a, b)
  return jnp.sum(cos ** 2) / cos.shape[0]


def chance_overlap(p: int, q: int, n: int = 20) -> float:
  """The mean overlap of a random p-dim and a random q-dim subspace of R^n."""
  return max(p, q) / n


def union_span(bases) -> np.ndarray | None:
  """An orthonormal basis of the sum of the column spaces of `bases` (None for none): the
  span a set of planted tasks plants together."""
  if not bases:
    return None
  u, s, _ = np.linalg.svd(np.concatenate([np.asarray(b, np.float64) for b in bases], axis=1),
                          full_matrices=False)
  return u[:, s > 1e-6 * s[0]].astype(np.float32)


def decoder_drift(model: DiscoSyn, reference, params, planted=None) -> dict[str, jax.Array]:
  """The decoder's movement in `params` from the one in `reference`, and its overlap with
  the `planted` span when there is one (module docstring)."""
  b0, b1 = synergy_basis(model, reference), synergy_basis(model, params)
  cos = principal_cosines(b0, b1)
  out = {"decoder/change": jnp.linalg.norm(b1 - b0) / jnp.linalg.norm(b0),
         "decoder/cos_min": cos.min(), "decoder/overlap_start": jnp.mean(cos ** 2)}
  out.update({f"decoder/cos_{k}": c for k, c in enumerate(cos, 1)})
  if planted is not None:
    out["decoder/overlap_planted"] = overlap(b1, planted)
  return out
