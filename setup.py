"""Build step that pyproject.toml cannot state: the scenes of ``sim/`` shipped in the wheel as ``vibkit/scenes/*.toml``.

``sim/`` stays the one copy in the repository; ``build_py`` copies its TOML files into the built package,
so ``vibkit.scenes`` finds them once installed.  Everything else is in pyproject.toml.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent


class BuildWithScenes(build_py):
    def run(self):
        super().run()
        target = Path(self.build_lib) / "vibkit" / "scenes"
        target.mkdir(parents=True, exist_ok=True)
        scenes = sorted((HERE / "sim").glob("*.toml"))
        if not scenes:
            raise RuntimeError(f"{HERE / 'sim'}: no scene (*.toml) to ship in vibkit/scenes/")
        for scene in scenes:
            shutil.copyfile(scene, target / scene.name)


setup(cmdclass={"build_py": BuildWithScenes})
