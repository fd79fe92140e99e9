"""Position-based layout synthesis (Weiss et al. 2018): rooms in, furniture layouts out.

The package knows nothing about images. Its input is a room (floor polygon in meters,
height, doors, windows) and a furnishing spec; its output is layout suggestions.
"""
from .builder import LayoutBuilder
from .errors import LayoutError
from .model import Model, State
from .solver import Layout, Solver, diversity, energy_terms, initial_state, residuals

__all__ = [
    "Layout",
    "LayoutBuilder",
    "LayoutError",
    "Model",
    "Solver",
    "State",
    "diversity",
    "energy_terms",
    "initial_state",
    "residuals",
]
