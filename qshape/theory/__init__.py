"""The qualitative shape theory's core: figures, labels, descriptions, matching and assignment."""
