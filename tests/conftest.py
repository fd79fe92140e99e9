import numpy as np
import pytest


@pytest.fixture
def rng():
    """Seeded generator: tests never touch global random state."""
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True, scope="session")
def _texture_cache(tmp_path_factory):
    """Made furniture textures go to a folder of the run's own, not the user's cache."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("STAGER_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        yield
