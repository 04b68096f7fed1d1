"""Pictures: training curves, policy videos, the hand along each synergy, offscreen
rendering."""
