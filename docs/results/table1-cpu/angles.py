# The exact script of the 2026-11-30 subspace comparison in docs/TRAINING_NOTES.md.
"""Principal-angle cosines between synergy subspaces: learned vs random start vs PCA of PPO's actions."""
import itertools
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[3]))  # the repository
from discosyn_jax.synergies import fitting
from discosyn_jax.synergies.diagnostics import principal_cosines

O = pathlib.Path(sys.argv[1]); seeds = [int(s) for s in sys.argv[2:]]
def basis(path):
    meta, p = fitting.read(path)
    return np.asarray(p["synergies"]["kernel"]).T  # (20, k)
cos = lambda a, b: np.asarray(principal_cosines(a, b))
fmt = lambda c: " / ".join(f"{x:.2f}" for x in c)
W = {}
for s in seeds:
    W[("learned", s)] = basis(O / f"discosyn3-l-set1-seed{s}")
    if (O / f"random3-l-set1-seed{s}/final").exists(): W[("random", s)] = basis(O / f"random3-l-set1-seed{s}")
    for k in (3, 4, 6):
        f = O / f"synergies-set1-seed{s}/pca{k}.npz"
        if f.exists(): W[(f"pca{k}", s)] = basis(f)
for s in seeds:
    for a, b in (("random", "learned"), ("random", "pca3"), ("learned", "pca3"), ("random", "pca6"), ("learned", "pca6")):
        if (a, s) in W and (b, s) in W: print(f"seed {s}: {a} vs {b}: {fmt(cos(W[(a, s)], W[(b, s)]))}")
for kind in ("random", "learned", "pca3"):
    for s, t in itertools.combinations(seeds, 2):
        if (kind, s) in W and (kind, t) in W: print(f"{kind} seed {s} vs seed {t}: {fmt(cos(W[(kind, s)], W[(kind, t)]))}")
# chance level: two random 3-D subspaces of R^20
rng = np.random.default_rng(0)
c = np.array([cos(rng.normal(size=(20, 3)), rng.normal(size=(20, 3))) for _ in range(2000)])
print("two random 3-D subspaces of R^20, mean cosines:", fmt(c.mean(0)))
c6 = np.array([cos(rng.normal(size=(20, 3)), rng.normal(size=(20, 6))) for _ in range(2000)])
print("random 3-D vs random 6-D, mean cosines:", fmt(c6.mean(0)))
