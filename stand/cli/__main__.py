"""``python -m stand.cli``."""

import sys

from stand.cli import main

sys.exit(main())
