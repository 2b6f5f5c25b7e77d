"""Tiles of the cell: shapes, physical tiles, per-episode variants and their collision pieces."""
