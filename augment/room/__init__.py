"""The room: its wall height, and the furniture fitted to the measured floor."""
