"""Code generation: rule base -> lookup table -> embeddable C and pure-Python source.

Installed as ``fuzzkit.codegen``. Reads the fuzzy core (:mod:`fuzzkit.fuzzy`) only; the code it
generates imports nothing from fuzzkit.
"""
