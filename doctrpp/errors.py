"""Errors the command line reports as one line with a non-zero exit."""


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""
