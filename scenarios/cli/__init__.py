"""The `homer` command line (`scenarios.cli.main`), with one module of commands per area beside it."""
