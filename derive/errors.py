"""The one exception type users see: a scene or option that cannot be accepted."""

from __future__ import annotations

import enum
import unicodedata

#: Longest file name, key or message shown; longer parts are cut with "...".
MAX_PART = 120
MAX_MESSAGE = 400


def one_line(text: object, limit: int = MAX_PART) -> str:
    """``text`` as one printable line: control and other invisible characters
    escaped (``\\n``, ``\\x1b``, ``\\u202e``), cut to ``limit`` characters.

    Scene files are untrusted: a key may hold a newline or a terminal escape
    sequence, and it must not break the one-line error or the user's terminal.
    """
    out = []
    for ch in str(text):
        if ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif unicodedata.category(ch)[0] in "CZ" and ch != " ":
            out.append(ch.encode("unicode_escape").decode("ascii"))
        else:
            out.append(ch)
    s = "".join(out)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def show(value: object, limit: int = 60) -> str:
    """A short ``repr`` of a rejected value for an error message (an enum member as its word: ``'free'``)."""
    if isinstance(value, enum.Enum):
        value = value.value
    text = repr(value)
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return one_line(text, limit)


class SceneError(ValueError):
    """A scene file or a command-line option was rejected.

    The message is a single line naming the file, the key, the bad value and
    what would be accepted, e.g.::

        scenes/x.toml: springs[1].between: 'm9': not a mass; accepted: 'm1', 'm2', 'wall'

    Parameters
    ----------
    file : str or None
        The scene file as the user gave it (None for command-line options).
    key : str or None
        The dotted key (``springs[1].between``) or option (``--dt``).
    message : str
        ``<value repr>: <why>; accepted: <what>``. Whatever it holds, the
        final message is one printable line.
    """

    def __init__(self, file: str | None, key: str | None, message: str):
        self.file = file
        self.key = key
        self.detail = message
        where = ": ".join(one_line(p) for p in (file, key) if p)
        body = one_line(message, MAX_MESSAGE)
        super().__init__(f"{where}: {body}" if where else body)
