"""How far a linear decoder reaches with z bounded: for each actuator, the largest |W^T z|
over |z_i| <= 1 (the sum of its column's absolute weights), and W's singular values:

  python docs/results/q-activation/reach.py RECORD...   # folders holding a decoder.npz
"""

import pathlib
import sys

import numpy as np

from discosyn_jax.synergies import fitting

for folder in map(pathlib.Path, sys.argv[1:]):
  _, params = fitting.read(folder / "decoder.npz")
  kernel = np.asarray(params["synergies"]["kernel"])  # (b, actions)
  reach = np.abs(kernel).sum(0)
  print(f"{folder.parent.name}/{folder.name}: singular values "
        f"{' '.join(f'{s:.2f}' for s in np.linalg.svd(kernel, compute_uv=False))}; reach per "
        f"actuator min {reach.min():.2f} median {np.median(reach):.2f} max {reach.max():.2f}")
