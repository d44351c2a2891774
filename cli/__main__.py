"""`python -m tailor.cli` runs the `tailor` command."""

import sys

from tailor.cli.main import main

sys.exit(main())
