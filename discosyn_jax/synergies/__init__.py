"""Synergies: PCA / autoencoder fits and synergy files, the priors a decoder starts
from, the cross-seed overlap of learned subspaces, and the decoder's movement."""
