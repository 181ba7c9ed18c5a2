"""``python -m comgrasp_pin.cli``: the `comgrasp` command."""

import sys

from comgrasp_pin.cli import main

sys.exit(main())
