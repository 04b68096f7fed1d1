"""The agent: the one Flax module (policy heads, values, the shared decoder, the
discriminator), the chain obs -> z -> a and its log-prob, the PPO losses and optimiser."""
