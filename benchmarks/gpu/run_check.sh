#!/usr/bin/env bash
# On the device machine, from the repository root (the device tool's working tree), with the
# wheels of wheels.sh carried in .whl/: install them beside the image's jax, then run the
# prepared GPU check into $OUT. Arguments go to gpu_check.py (e.g. --budget-s 420).
# The compile cache is an ignored folder of the tree, which a warm machine keeps for the next
# call (in /tmp, call 1's cache did not spare call 2 its start, 2026-12-04).
set -o pipefail
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH="/tmp/site:$PWD" PYTHONUNBUFFERED=1 DISCOSYN_JAX_CACHE="$PWD/runs/jax-cache"
# MJX's own advice for NVIDIA GPUs: let Triton take every matrix product
export XLA_FLAGS="${XLA_FLAGS:-} --xla_gpu_triton_gemm_any=true"
OUT="${OUT:-runs/gpu_check}"
mkdir -p "$OUT"
python3 benchmarks/gpu/gpu_check.py --out "$OUT" "$@" 2>&1 | tee "$OUT/log.txt"
