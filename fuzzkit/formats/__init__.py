"""File formats: the rule-base YAML reader, writer and JSON Schema, and loading by name.

Imports only :mod:`fuzzkit.fuzzy` (the model knows no format; readers build it, writers read it).
"""
