"""The shipped scenario files E1.yaml, E2.yaml, E3.yaml (the paper's experiments)."""
