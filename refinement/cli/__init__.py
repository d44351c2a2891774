"""The `tailor` command line (`main`), one module per subcommand."""

from tailor.refinement.cli.main import main

__all__ = ["main"]
