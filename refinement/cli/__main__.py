"""`python -m tailor.refinement.cli` runs the `tailor` command."""

import sys

from tailor.refinement.cli.main import main

sys.exit(main())
