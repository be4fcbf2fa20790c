"""Errors a user can act on. Tracebacks are for bugs; these print one line."""

from __future__ import annotations


class CaseError(Exception):
    """A malformed case: names the file, the key and what was expected (CLI exit status 2)."""

    def __init__(self, file: str, key: str, expected: str):
        self.file, self.key, self.expected = str(file), key, expected
        super().__init__(f"{self.file}: {key}: {expected}")


class Instability(Exception):
    """The run went unstable (CLI exit status 1); the last good output is kept."""

    def __init__(self, step: int, time: float, particle: int, reason: str):
        self.step, self.time, self.particle, self.reason = step, time, particle, reason
        super().__init__(
            f"unstable at step {step}, t = {time:.6g} s: {reason} (worst particle id {particle})"
        )


class OutputError(Exception):
    """Output could not be written (exists already, no permission, disk full)."""
