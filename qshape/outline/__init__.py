"""Outlines: slope-comparison simplification of dense contours and corner fitting."""
