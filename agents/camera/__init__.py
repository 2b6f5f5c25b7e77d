"""Policies that read the two camera images: object crops, the crop scorer, its cloning, poses."""
