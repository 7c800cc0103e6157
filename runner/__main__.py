"""`python -m runner` is the `scenario` command."""

import sys

from runner.cli.main import main

sys.exit(main())
