"""``python -m flexval.validation.cli``: the ``flexval`` command."""

import sys

from flexval.validation.cli import main

sys.exit(main())
