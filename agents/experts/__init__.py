"""Scripted reference controllers of the low-level rungs and the theory as an objects policy."""
