import os
from pathlib import Path

import pytest

from support.cli import run  # noqa: F401  (the fixture `run`: vibkit.cli.main in-process, for every test)

ROOT = Path(__file__).resolve().parents[1]
SIM = ROOT / "sim"

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def reference_scene():
    from vibkit.model.scene import load_scene

    return load_scene(SIM / "thesis-kinematics.toml")


@pytest.fixture(scope="session")
def model(reference_scene):
    from vibkit.model.escalator import EscalatorModel

    return EscalatorModel(reference_scene)
