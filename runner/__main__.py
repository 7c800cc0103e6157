"""`python -m runner` is the `scenario` command."""

import sys

from .cli import main

sys.exit(main())
