"""A pymunk planar two-link arm in contact: a plant that knows nothing of fuzzy logic."""
