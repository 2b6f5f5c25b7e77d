"""Benchmarks of the qshape library: describing and assigning many tiles, robustness at its caps."""
