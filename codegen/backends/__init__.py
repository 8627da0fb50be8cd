"""Code-generation targets, one folder per language (templates and a small config)."""
