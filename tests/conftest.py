import atexit
import os
import shutil
import tempfile
from pathlib import Path

import pytest

from support.cli import run  # noqa: F401  (the fixture `run`: vibkit.cli.main in-process, for every test)

ROOT = Path(__file__).resolve().parents[1]
SIM = ROOT / "sim"

os.environ.setdefault("MPLBACKEND", "Agg")

# the files vibkit keeps between runs (vibkit.runtime.user_cache: profile scenes, worn-link signatures) go to a
# folder of this test session, not the user's cache: every session derives them afresh
os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="vibkit-tests-cache-")
atexit.register(shutil.rmtree, os.environ["XDG_CACHE_HOME"], ignore_errors=True)


@pytest.fixture(scope="session")
def reference_scene():
    from vibkit.model.scene import load_scene

    return load_scene(SIM / "thesis-kinematics.toml")


@pytest.fixture(scope="session")
def model(reference_scene):
    from vibkit.model.escalator import EscalatorModel

    return EscalatorModel(reference_scene)
