"""Build step that pyproject.toml cannot state: the scenes of ``sim/`` shipped in the wheel as ``vibkit/scenes/*.toml``,
and the example files of ``data/field/`` and ``data/fleet-example/`` (with their provenance, ``data/README.md``) as
``vibkit/datasets/files/``.

``sim/`` and ``data/`` stay the one copy in the repository; ``build_py`` copies them into the built package,
so ``vibkit.scenes`` and ``vibkit.datasets`` find them once installed.  Nothing else of ``data/`` ships (the
third-party and device files keep their own licences).  Everything else is in pyproject.toml.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent


class BuildWithScenesAndData(build_py):
    def run(self):
        super().run()
        target = Path(self.build_lib) / "vibkit" / "scenes"
        target.mkdir(parents=True, exist_ok=True)
        scenes = sorted((HERE / "sim").glob("*.toml"))
        if not scenes:
            raise RuntimeError(f"{HERE / 'sim'}: no scene (*.toml) to ship in vibkit/scenes/")
        for scene in scenes:
            shutil.copyfile(scene, target / scene.name)
        files = Path(self.build_lib) / "vibkit" / "datasets" / "files"
        for folder in ("field", "fleet-example"):
            src = HERE / "data" / folder
            if not src.is_dir():
                raise RuntimeError(f"{src}: missing (the example files shipped in vibkit/datasets/files/)")
            shutil.copytree(src, files / folder, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))
        shutil.copyfile(HERE / "data" / "README.md", files / "README.md")


setup(cmdclass={"build_py": BuildWithScenesAndData})
