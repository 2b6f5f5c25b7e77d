"""Agents driving the cell: scripted baseline, perception, training, evaluation, benchmarks."""
