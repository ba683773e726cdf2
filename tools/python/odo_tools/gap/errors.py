"""One error type for every bad input: it names the file and, where there is one, the line."""

from __future__ import annotations

from pathlib import Path


class GapInputError(Exception):
    """Bad input data; str() is 'file:line: why' (line omitted when it does not apply)."""

    def __init__(self, path: str | Path, why: str, line: int | None = None) -> None:
        self.path = str(path)
        self.line = line
        self.why = why
        where = f"{self.path}:{line}" if line is not None else self.path
        super().__init__(f"{where}: {why}")

    def __reduce__(self):
        # pickled by its own arguments: one raised in a worker process (gap/par.py) must rebuild
        # in the parent, whose pool thread otherwise fails on it and the diagnosis waits for ever
        return type(self), (self.path, self.why, self.line)
