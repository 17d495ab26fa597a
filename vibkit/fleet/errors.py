"""Errors of the fleet history: one-line messages about its inputs (database, catalogue, options)."""

__all__ = ["DuplicateRecordingError", "FleetError"]


class FleetError(ValueError):
    """A problem with the fleet's inputs (database, catalogue, options), in one line."""


class DuplicateRecordingError(FleetError):
    """The recording is already stored (same SHA-256); ``existing`` is the stored :class:`Measurement`."""

    def __init__(self, message, existing):
        super().__init__(message)
        self.existing = existing
