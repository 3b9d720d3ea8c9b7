"""``python -m mvtrack``."""

import sys

from mvtrack.cli import main

sys.exit(main())
