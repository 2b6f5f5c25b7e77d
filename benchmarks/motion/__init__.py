"""Benchmarks of the planners: full designs picked and placed, ABB's standard cycle."""
