"""The exceptions of the scg package."""

from __future__ import annotations

from typing import Optional


class ScgError(Exception):
    """Base class of every error scg raises."""


class SceneError(ScgError, ValueError):
    """A scene was rejected: the file, the key and (when the key is in the file) its line.

    ``str(err)`` is the message ``scg run`` prints, e.g.
    ``cases/elbow.toml:12: key `groups[0].diameter`: must be positive``.
    """

    def __init__(self, text: str, file: str, key: Optional[str], line: Optional[int], message: str):
        super().__init__(text)
        self.file = file
        self.key = key
        self.line = line
        self.message = message


class CheckError(ScgError, ValueError):
    """``scg check`` found an error: the run would be meaningless and is refused."""

    def __init__(self, findings: list):
        super().__init__("\n".join(findings))
        self.findings = list(findings)


class RunError(ScgError, RuntimeError):
    """A run stopped on an error (a sink could not write, the state went bad)."""


class RecordingError(ScgError, OSError):
    """A recording could not be read (not an MCAP file of scg's, damaged)."""
