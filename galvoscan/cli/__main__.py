"""``python -m galvoscan.cli``."""

import sys

from . import main


sys.exit(main())
