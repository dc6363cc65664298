"""Errors that the CLI reports as one line on stderr with exit status 2."""


class MtbmjError(Exception):
    """Base class: a user-facing problem with a clear one-line cause."""


class ConfigError(MtbmjError):
    """A configuration is missing a key, misspells one, or holds an invalid value."""


class RunError(MtbmjError):
    """A run diverged (NaN, a MuJoCo warning) or could not be completed."""
