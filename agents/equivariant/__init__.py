"""The rotation-equivariant pixel policy of the decision rungs: its data, network and training."""
