"""The pair scorer: one network over every (tile, slot) pair, its rows, cloning, RL policy."""
