"""`python -m runner` is the `scenario` command."""

import sys

from runner.cli.entry import main

sys.exit(main())
