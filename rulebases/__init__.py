"""Shipped rule bases (YAML), loadable by name with ``fuzzkit.load(name)``."""

if __name__ != "fuzzkit.rulebases":  # this repository folder imported as a top-level package
    raise ImportError(
        f"{__name__!r} is the source folder of fuzzkit.rulebases; import fuzzkit.rulebases "
        "(pip install -e . maps this folder into fuzzkit)"
    )
