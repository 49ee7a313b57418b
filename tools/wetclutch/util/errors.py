"""Errors the command line reports as a message (exit 2) rather than a traceback."""


class LogError(Exception):
    """A CAN log or capture that cannot be used; the message says where."""
