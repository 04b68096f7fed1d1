"""Experiment presets and scripts (benchmarks, calibration)."""
