"""Stability analysis of the force loop: its linear model, bounds on the fuzzy surface, and a
certificate over contact stiffness and latency (docs/stability.md)."""
