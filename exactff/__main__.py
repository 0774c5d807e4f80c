"""``python -m exactff``: the ``exactff`` command."""

import sys

from .cli import main

sys.exit(main())
