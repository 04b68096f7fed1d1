#!/bin/bash
# 2026-12-02: learning per env step before (reference physics, 4 ms x 10) and after
# (the fast profile's valves: 8 ms x 5, refsafe off), 2 seeds each, on one 2-core VM.
# Each side ran from a copy of HEAD 45e6940 (the "after" copy with xml/arena.xml's timestep
# 0.008 + refsafe="disable" and TaskConfig.n_substeps 5: exactly the fast profile of set #1),
# so nothing else differed. The configs here were then upgraded (`discosyn upgrade`) and the
# "after" ones marked "physics": "fast". With today's code the same runs are:
for physics in reference fast; do
  for seed in 0 1; do
    # DiscoSyn3-L on set #1 at the cpu scale (1.54 M env steps)
    discosyn experiment discosyn-set1 --seeds $seed --methods DiscoSyn3-L --out runs/$physics   # with TrainConfig physics=$physics
    # full-action PPO on valve3, 256 k env steps
    discosyn train --preset valve3-ppo --steps 100 --eval-every 20 --seed $seed --physics $physics --out runs/$physics/valve3-ppo-seed$seed
  done
done
