"""``python -m billiard.cli``: the command line."""

import sys

from billiard.cli import main

sys.exit(main())
