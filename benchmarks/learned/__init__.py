"""Experiments with learned policies: training rows, evaluation, curves."""
