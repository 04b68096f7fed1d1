#!/usr/bin/env bash
# The wheels a bare GPU machine's image lacks, for Python 3.12 on x86-64 Linux, in .whl/
# (ignored by git; copied to the GPU machine with the working tree). The image already holds
# jax 0.11.2 (CUDA 13), flax, optax, orbax-checkpoint, chex, numpy, scikit-learn, matplotlib,
# imageio, tqdm, absl-py and etils. brax imports jaxopt (brax.generalized) and ml_collections
# at import time. warp-lang (the warp extra's pin): MJX's Warp implementation, for
# `gpu_check.py --impls warp jax` (149 MB of the wheels).
set -euo pipefail
cd "$(dirname "$0")/../.."
for ignored in /.whl/ /.whl-parts/; do
  grep -qx "$ignored" .git/info/exclude 2>/dev/null || echo "$ignored" >> .git/info/exclude
done
WHEELS=(mujoco==4.0.0 mujoco-core==4.0.0 mujoco-mjx==3.17.0 brax==0.14.2 jaxopt==0.8.5
        ml_collections==1.1.0 tensorboardX==2.6.5 trimesh==5.2.0 warp-lang==1.18.0)
PYTHON="${PYTHON:-python3}"
"$PYTHON" -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
  --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
  --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 --platform manylinux1_x86_64 \
  --platform any -d .whl "${WHEELS[@]}"
du -ch .whl/*.whl | tail -1
# what one call carries beside the tracked tree: .whl-parts/1, 2, ... (wheel_parts.py)
"$PYTHON" benchmarks/gpu/wheel_parts.py split --mb "${PART_MB:-25}"
