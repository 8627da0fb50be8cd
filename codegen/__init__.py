"""Code generation: rule base -> lookup table -> embeddable C and pure-Python source.

Installed as ``fuzzkit.codegen``. Reads the fuzzy core (:mod:`fuzzkit.fuzzy`) only; the code it
generates imports nothing from fuzzkit.
"""

if __name__ != "fuzzkit.codegen":  # this repository folder imported as a top-level package
    raise ImportError(
        f"{__name__!r} is the source folder of fuzzkit.codegen; import fuzzkit.codegen "
        "(pip install -e . maps this folder into fuzzkit)"
    )
