import numpy as np
import pytest


@pytest.fixture
def rng():
    """Seeded generator: tests never touch global random state."""
    return np.random.default_rng(12345)
