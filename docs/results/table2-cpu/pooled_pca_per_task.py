# The exact script of the 2026-12-01 measurement in docs/TRAINING_NOTES.md (weight_pull and the
# fitted spaces): the share of each task's actions' squared deviation from the pooled mean that
# the pooled PCA-k subspace holds. Argument: a fit folder's actions.npz (not committed: rerun
# `discosyn experiment baselines-set2` to make it).
import sys
import numpy as np
d = np.load(sys.argv[1]); X = np.concatenate([d[k] for k in d.files]); mu = X.mean(0)
_, _, Vt = np.linalg.svd(X - mu, full_matrices=False)
for k in (3, 4, 6):
  V = Vt[:k].T
  held = {t: 1 - (((d[t] - mu) - (d[t] - mu) @ V @ V.T) ** 2).sum() / ((d[t] - mu) ** 2).sum()
          for t in d.files}
  print(k, "; ".join(f"{t} {h:.2f}" for t, h in held.items()))
