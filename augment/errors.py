"""The image side's kinds of Stager's one error root (:class:`layout.errors.StagerError`).

Callers catch ``StagerError`` once and map ``.kind`` (the CLI to exit status 2, the web
app to a job's error or an HTTP status).
"""
from layout.errors import LayoutError, StagerError, UsageError


class CalibrationError(StagerError):
    """A photo that cannot be calibrated: unreadable, no board, a board that gives no
    trustworthy camera."""

    kind = "calibration"


class SegmentationError(StagerError):
    """A floor model, floor mask or click that cannot be used."""

    kind = "segmentation"


class FurnishError(StagerError):
    """Bad input that no single stage reports: no floor, a floor too small for any
    furniture, an output folder that cannot be written."""

    kind = "furnish"


class UploadError(StagerError):
    """An upload the web app refuses before any work; ``status`` is the HTTP code."""

    kind = "upload"

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


__all__ = ["StagerError", "UsageError", "LayoutError", "CalibrationError", "SegmentationError", "FurnishError",
           "UploadError"]
