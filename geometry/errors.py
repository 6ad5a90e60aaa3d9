"""The one error type for bad input: it names the file, the field and the value."""

from __future__ import annotations

COMMAND_LINE = "<command line>"
"""The source a :class:`SceneError` names for a value given on the command line (or in a
call standing for it), where a scene file names its path."""


class SceneError(ValueError):
    """Invalid scene input.

    Parameters
    ----------
    source : str
        The scene file (or ``<name>`` of a built-in or in-memory scene).
    field : str
        Dotted path of the offending field, e.g. ``flexures.e12.radius``.
    value : object
        The offending value.
    reason : str
        What is wrong with it, in plain words.
    """

    def __init__(self, source: str, field: str, value: object, reason: str):
        self.source, self.field, self.value, self.reason = source, field, value, reason
        super().__init__(f"{source}: field '{field}' = {value!r}: {reason}")


def did_you_mean(word: object, options) -> str:
    """`` (did you mean 'x'?)`` naming the option closest to ``word``, or ``""``.

    Closeness is :func:`difflib.get_close_matches`' ratio (at least 0.6), case
    ignored: a misspelt field or choice names the one it most likely meant.
    """
    import difflib

    if not isinstance(word, str) or not word:
        return ""
    names = {str(o).lower(): str(o) for o in options}
    close = difflib.get_close_matches(word.lower(), list(names), n=1, cutoff=0.6)
    return f" (did you mean {names[close[0]]!r}?)" if close else ""
