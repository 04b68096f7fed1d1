#!/bin/bash
# Table I (set #1) + sparse at the cpu scale, 3 seeds, as two interleaved queues
D=discosyn; O=runs/table1-cpu
cd "$(git rev-parse --show-toplevel)"
if [ "$1" = A ]; then
  $D experiment discosyn-set1 --seeds 0 --out $O && \
  $D experiment baselines-set1 --seeds 1 --out $O && \
  $D experiment discosyn-set1 --seeds 2 --out $O
else
  $D experiment baselines-set1 --seeds 0 --out $O && \
  $D experiment discosyn-set1 --seeds 1 --out $O && \
  $D experiment baselines-set1 --seeds 2 --out $O && \
  until [ -d $O/discosyn3-l-set1-seed2/final ]; do sleep 30; done && \
  $D experiment sparse --seeds 0 1 2 --out $O
fi
echo "queue $1 finished rc=$?"
