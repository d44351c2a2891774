"""The `tailor` command line (`main`), one module per subcommand."""

from tailor.cli.main import main

__all__ = ["main"]
