"""Shipped rule bases (YAML), loadable by name with ``fuzzkit.load(name)``."""
