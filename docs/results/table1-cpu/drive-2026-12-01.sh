#!/bin/bash
# Table I seeds 1-2: the rows still missing, as two queues of 8 runs
D=discosyn; O1=runs/table1-cpu
cd "$(git rev-parse --show-toplevel)"
if [ "$1" = A ]; then
  $D experiment baselines-set1 --seeds 2 --out $O1 --methods AE4 PCA6 AE6
  $D experiment discosyn-set1 --seeds 2 --out $O1 --methods DiscoSyn3-NL Random3-NL
  $D experiment discosyn-set1 --seeds 1 --out $O1 --methods DiscoSyn4-NL
  $D experiment baselines-set1 --seeds 2 --out $O1 --methods PCA4
else
  $D experiment baselines-set1 --seeds 1 --out $O1 --methods AE4 PCA6 AE6
  $D experiment discosyn-set1 --seeds 1 --out $O1 --methods Random4-NL
  $D experiment discosyn-set1 --seeds 2 --out $O1 --methods DiscoSyn4-NL Random4-NL
  $D experiment baselines-set1 --seeds 1 --out $O1 --methods PCA4
fi
echo "queue $1 finished"
