"""The exceptions of crackle, with the command line's exit codes (``crackle --help``)."""
import re

# file:line: key.path: rest  (the line and the key path may be absent)
_WHERE = re.compile(r"^(?P<file>[^:\n]+?)(?::(?P<line>\d+))?: (?:(?P<key>[A-Za-z_][\w.\[\]]*): )?(?P<rest>.*)$", re.S)


class CrackleError(Exception):
    """Base of crackle's errors; ``exit_code`` is what ``crackle`` exits with for it."""

    exit_code = 1


class SceneError(CrackleError, ValueError):
    """A bad scene (or option): the command line's exit code 2.

    ``file``, ``line`` (None when the message names none, e.g. for an override) and ``key`` (the
    key path, None when the message names none) come from the message ``file:line: key.path: ...``.
    """

    exit_code = 2

    def __init__(self, message):
        super().__init__(message)
        self.message = message
        match = _WHERE.match(message)
        self.file = match.group("file") if match else None
        self.line = int(match.group("line")) if match and match.group("line") else None
        key = match.group("key") if match else None
        # "expected ..." after the file is the reason, not a key.
        self.key = key if key and key not in ("expected", "error") else None


class SolverError(CrackleError, RuntimeError):
    """A solver failed, memory ran out, or cases of a study failed: exit code 3."""

    exit_code = 3


class IoError(CrackleError, OSError):
    """A file could not be read or written: exit code 4. A missing scene file is one too, though
    the command line counts it as bad input (exit code 2): ``exit_code`` is then 2."""

    exit_code = 4

    def __init__(self, message, exit_code=None):
        super().__init__(message)
        self.message = message
        if exit_code is not None:
            self.exit_code = exit_code

    def __str__(self):
        return self.message
