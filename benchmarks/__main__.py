"""``python -m benchmarks run|report|list``: the reconstruction benchmark runner."""

import sys

from .runner.cli import main

sys.exit(main())
