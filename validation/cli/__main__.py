"""``python -m flexval.validation.cli``: the ``flexval`` command."""

import sys

from . import main

sys.exit(main())
