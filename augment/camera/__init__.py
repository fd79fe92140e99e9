"""The camera: the board, its printable PDF, finding it in a photo, and the calibration
every later stage reads (:class:`augment.camera.calibration.Calibration`)."""
