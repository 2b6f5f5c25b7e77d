"""Synthetic pictures: rendered designs and tiles, and what a real line adds to them."""
