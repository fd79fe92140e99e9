"""The furnishing pipeline's own bad-input error, apart from the pipeline so that the
command line can catch it without importing the pipeline (and the solver, and
matplotlib) for a command that does not furnish."""


class FurnishError(ValueError):
    """Bad input that no single stage reports: no floor, a floor too small for any
    furniture, an output folder that cannot be written. The message says what and why."""
