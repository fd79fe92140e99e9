"""Position-based layout synthesis (Weiss et al. 2018): rooms in, furniture layouts out.

The package knows nothing about images. Its input is a room (floor polygon in meters,
height, doors, windows) and a furnishing spec; its output is layout suggestions.

The names below load on first use: importing a light submodule (``layout.geometry``,
``layout.command``) should not compile the solver's numba kernels.
"""
import importlib

_HOMES = {
    "Layout": "solver",
    "LayoutBuilder": "builder",
    "LayoutError": "errors",
    "Model": "model",
    "Solver": "solver",
    "State": "model",
    "clearance_intrusions": "solver",
    "diversity": "solver",
    "energy_terms": "solver",
    "initial_state": "solver",
    "residuals": "solver",
}

__all__ = sorted(_HOMES)


def __getattr__(name):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *_HOMES})
