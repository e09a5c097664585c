"""One module per ``teachbot`` subcommand (see ``dialog/cli.py``)."""
