"""``python -m benchmarks.public_data``: see the package docstring."""

import sys

from .cli import main

sys.exit(main())
