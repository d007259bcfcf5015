"""``python -m stand.cli``."""

import sys

from stand.cli import entry

sys.exit(entry())
