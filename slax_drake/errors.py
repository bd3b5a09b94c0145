"""Exceptions that the command line reports as one line with exit code 2.

Every error caused by what a user gave us (a config, a scene file, a request that cannot be met)
derives from :class:`UserError`. Anything else is a bug and keeps its traceback.
"""


class UserError(Exception):
    """A problem with the user's input; printed as one line, exit code 2."""


class ConfigError(UserError):
    """A scenario YAML file is malformed or holds an impossible value."""


class SceneFileError(UserError):
    """A scene JSON file is malformed, has the wrong schema version or out-of-range values."""


class SceneGenerationError(UserError):
    """A scene could not be completed within the retry budget."""
