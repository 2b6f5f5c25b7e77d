"""Behaviour cloning commands: python -m apps.bc {decision,camera,objects} ...."""
