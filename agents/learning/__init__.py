"""Learning machinery of the learned policies: demonstrations, cloning, RL helpers, wrappers."""
