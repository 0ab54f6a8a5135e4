"""``python -m rockbench.cli``: the same as the ``rockbench`` command."""

import sys

from rockbench.cli import main

sys.exit(main())
