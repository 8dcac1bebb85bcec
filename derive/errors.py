"""The one exception type users see: a scene or option that cannot be accepted."""

from __future__ import annotations


class SceneError(ValueError):
    """A scene file or a command-line option was rejected.

    The message is a single line naming the file, the key, the bad value and
    what would be accepted, e.g.::

        scenes/x.toml: springs[1].between: 'm9' is not a mass; accepted: 'm1', 'm2', 'wall'
    """

    def __init__(self, file: str | None, key: str | None, message: str):
        self.file = file
        self.key = key
        self.detail = message
        where = ": ".join(p for p in (file, key) if p)
        super().__init__(f"{where}: {message}" if where else message)
