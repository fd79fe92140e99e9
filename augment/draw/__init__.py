"""Pictures for people: the calibration, floor and height overlays, and the contact sheet."""
