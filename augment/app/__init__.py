"""The front ends: the ``stage`` command line, and the web app with its job queue."""
