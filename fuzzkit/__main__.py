"""``python -m fuzzkit``: the same as the ``fuzzkit`` command."""

from fuzzkit.cli import main

raise SystemExit(main())
