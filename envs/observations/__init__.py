"""Observations of MosaicAssembly-v0: the sensors' Dict space, objects and perception rows."""
