"""The project's typed errors: every bad input ends as one of these, with a one-line message.

Library code raises them; the CLI turns them into one clear line on stderr and a non-zero exit.
"""


class DecoyError(Exception):
    """Base of every error a user can cause by giving bad input."""


class WorldError(DecoyError):
    """A mesh or map that cannot be read or used (missing, corrupt, wrong scale or axis)."""


class GraphError(DecoyError):
    """A waypoint graph file that is missing, corrupt, of another version, or a bad query."""


class EstaError(DecoyError):
    """An ESTA match file that cannot be read: corrupt, truncated, wrong schema, missing round."""


class OutputError(DecoyError):
    """An output path that cannot be written."""


class ModelError(DecoyError):
    """A damage model that cannot be used: missing, corrupt or incompatible files or inputs."""


class CompareError(DecoyError):
    """Two evaluation runs that cannot be compared: a missing or broken table, other data, other
    metrics, nothing in common."""


class DownloadError(DecoyError):
    """A file that cannot be fetched or fails verification: HTTP error, timeout, short body."""


def describe_bug(error: BaseException) -> tuple[str, str]:
    """An unexpected exception in one line: ("Type: first line of its message", "file.py:line"
    where it was raised, or "" when unknown), for reports that must not show a traceback."""
    import traceback
    from pathlib import Path

    frame = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
    where = f"{Path(frame.filename).name}:{frame.lineno}" if frame else ""
    text = str(error).splitlines()[0] if str(error) else ""
    return f"{type(error).__name__}: {text}", where
