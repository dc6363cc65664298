"""Errors that the CLI reports as one line on stderr with exit status 2."""


class MtbmjError(Exception):
    """Base class: a user-facing problem with a clear one-line cause."""


class ConfigError(MtbmjError):
    """A configuration is missing a key, misspells one, or holds an invalid value."""


class FallbackWarning(UserWarning):
    """A faster path could not be used here (numba missing, a law without a compiled form, more
    contact patches than the compiled rolling callback holds); the run goes on along the Python
    path, with the same results. Not a failure: the command line shows it as a one-line note."""


class RunError(MtbmjError):
    """A run diverged (NaN, a MuJoCo warning) or could not be completed."""
