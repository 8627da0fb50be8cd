"""``python -m fuzzkit``: the same as the ``fuzzkit`` command."""

from fuzzkit.cli import console_main

console_main()
