"""``python -m benchmarks.search_baselines``: see the package docstring."""

import sys

from .cli import main

sys.exit(main())
