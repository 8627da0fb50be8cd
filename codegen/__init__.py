"""Code generation: rule base -> lookup table -> embeddable C and pure-Python source."""
