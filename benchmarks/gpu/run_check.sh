#!/usr/bin/env bash
# On a bare GPU machine, from the repository root, with the wheels of wheels.sh in .whl/:
# install them beside the image's jax, then run the prepared GPU check into $OUT (default
# runs/gpu_check). Arguments go to gpu_check.py (e.g. --budget-s 420); docs/SCALING.md.
# The compile cache is an ignored folder of the tree (runs/jax-cache), kept for a later run
# on the same machine (a cache in a temporary folder did not spare a second run its start,
# 2026-12-04).
set -o pipefail
# wheels that came in parts over earlier calls (wheel_parts.py): joined and checked first
if [ -d .whl-parts ]; then python3 benchmarks/gpu/wheel_parts.py join || exit 2; fi
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH="/tmp/site:$PWD" PYTHONUNBUFFERED=1 DISCOSYN_JAX_CACHE="$PWD/runs/jax-cache"
# MJX's own advice for NVIDIA GPUs: let Triton take every matrix product
export XLA_FLAGS="${XLA_FLAGS:-} --xla_gpu_triton_gemm_any=true"
OUT="${OUT:-runs/gpu_check}"
mkdir -p "$OUT"
python3 benchmarks/gpu/gpu_check.py --out "$OUT" "$@" 2>&1 | tee "$OUT/log.txt"
