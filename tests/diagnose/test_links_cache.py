"""`vibkit links --escalator` keeps the profile's scene and the worn link's signature runs in the user's cache folder
and never trusts a file planted at any path it derives: a planted scene, an empty file, a link to another file, a
file of another key under the right name, a file others may write, a cache folder that is a link.  Each run with
planted files gives the same result as the run without them, and the link targets are left as they were."""

import dataclasses
import hashlib
import json
import os
import shutil
import tempfile

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.cli import main
from vibkit.diagnose import link_signature
from vibkit.diagnose import links as links_mod
from vibkit.model.profile import parse_profile
from vibkit.model.scene import load_scene

from support.profiles import PROFILE_90

pytestmark = pytest.mark.slow

SPEED = 0.5


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """2.3 loops of the 90-link profile's chain with link 20 1 mm long (1 um of noise), and the profile."""
    folder = tmp_path_factory.mktemp("planted")
    profile = folder / "E90.toml"
    profile.write_text(PROFILE_90)
    base = tmp_path_factory.mktemp("scene-cache")
    mp = pytest.MonkeyPatch()
    mp.setenv("XDG_CACHE_HOME", str(base))
    try:
        scene = load_scene(links_mod.profile_scene_file(parse_profile(PROFILE_90, "E90.toml")))
    finally:
        mp.undo()
    pitch, n = scene.chain.link_pitch, scene.chain.n_rollers
    sc = dataclasses.replace(
        scene,
        chain=dataclasses.replace(scene.chain, worn_links=((20, pitch + 1e-3),)),
        outputs=dict(scene.outputs, variables=("delta",)),
    ).with_solver(closure="exact")
    settle = n * pitch / SPEED + 5.0
    ds = vibkit.simulate(sc, duration=settle + (2.3 * n + 3) * pitch / SPEED, progress=False)
    keep = ds.time.values >= settle
    rng = np.random.default_rng(20)
    rec = xr.Dataset(
        {"delta": ("time", ds.delta.values[keep] + rng.normal(0, 1e-6, keep.sum()), {"units": "m"})},
        coords={"time": ("time", ds.time.values[keep] - settle, {"units": "s"})},
    )
    rec.to_netcdf(folder / "rec.nc")
    return folder / "rec.nc", profile


def _links(rec, profile, cache, capsys, monkeypatch):
    """`vibkit links --escalator --json` with the cache folder ``cache`` and nothing kept in memory."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
    link_signature._run_map_cached.cache_clear()
    rc = main(["links", str(rec), "--escalator", str(profile), "--json"])
    out = capsys.readouterr().out
    assert rc == 0, out
    return json.loads(out)


def _files(cache):
    return sorted(p.relative_to(cache) for p in cache.rglob("*") if p.is_file() and not p.name.startswith("."))


def test_planted_files_at_every_derived_path_are_never_trusted(recording, tmp_path, capsys, monkeypatch):
    rec, profile = recording
    clean = tmp_path / "clean"
    truth = _links(rec, profile, clean, capsys, monkeypatch)
    assert truth["flagged"], truth
    derived = _files(clean / "vibkit")
    scenes = [p for p in derived if p.parts[0] == "scenes"]
    runs = [p for p in derived if p.parts[0] == "signatures"]
    assert len(scenes) == 1 and len(runs) == 3  # the healthy run, 1 mm and 0.5 mm
    # the profile's scene was once written to a shared temporary folder under a name anyone could compute
    text = (clean / "vibkit" / scenes[0]).read_text()
    old = os.path.join(tempfile.gettempdir(), f"vibkit-links-{hashlib.sha256(text.encode()).hexdigest()[:16]}.toml")
    other_scene = PROFILE_90.replace("n_links = 90", "n_links = 90\nroller_radius = 0.04")
    other_text = parse_profile(other_scene, "X.toml").scene_text("forward")
    decoy = tmp_path / "decoy"
    decoy.write_text("a file that is not vibkit's")
    decoy_bytes = decoy.read_bytes()

    def plant(cache, how):
        for rel in derived:
            path = cache / "vibkit" / rel
            path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            if how == "planted":  # a valid file of another scene / another run under the right name
                if rel in scenes:
                    path.write_text(other_text)
                else:
                    shutil.copy(clean / "vibkit" / runs[(runs.index(rel) + 1) % 3], path)
            elif how == "empty":
                path.write_bytes(b"")
            elif how == "symlink":
                path.symlink_to(decoy)
            elif how == "others may write":  # the right content, but writable by anyone
                shutil.copy(clean / "vibkit" / (runs[(runs.index(rel) + 1) % 3] if rel in runs else rel), path)
                if rel in scenes:
                    path.write_text(other_text)
                os.chmod(path, 0o666)
            elif how == "wrong content":  # the right header for its key, another payload
                data = (clean / "vibkit" / rel).read_bytes()
                path.write_bytes(data[:-8] + b"\x00" * 8 if rel in runs else data.replace(b"90", b"91"))
        if how == "folder is a link":  # the subfolders themselves lead elsewhere
            for sub in ("scenes", "signatures"):
                target = tmp_path / f"{sub}-elsewhere"
                shutil.copytree(cache / "vibkit" / sub, target)
                shutil.rmtree(cache / "vibkit" / sub)
                (cache / "vibkit" / sub).symlink_to(target)

    with open(old, "w") as f:  # what another user could plant where vibkit used to look
        f.write(other_text)
    try:
        for how in ("planted", "empty", "symlink", "others may write", "wrong content", "folder is a link"):
            cache = tmp_path / how.replace(" ", "-")
            plant(cache, how)
            got = _links(rec, profile, cache, capsys, monkeypatch)
            assert got == truth, how
            assert decoy.read_bytes() == decoy_bytes, how
            if how != "folder is a link":  # each planted file replaced by vibkit's own
                for rel in scenes:
                    path = cache / "vibkit" / rel
                    assert not path.is_symlink() and path.read_text() == text, how
                    assert os.stat(path).st_mode & 0o077 == 0
    finally:
        os.unlink(old)


def test_a_second_call_reads_the_kept_runs_instead_of_simulating(recording, tmp_path, capsys, monkeypatch):
    """With the runs kept, the signature is not simulated again, and gives the same result."""
    rec, profile = recording
    first = _links(rec, profile, tmp_path, capsys, monkeypatch)
    calls = []
    monkeypatch.setattr(link_signature, "_simulate_run_map", lambda *a: calls.append(a))
    second = _links(rec, profile, tmp_path, capsys, monkeypatch)
    assert calls == [] and second == first


def test_a_warm_call_loads_neither_the_model_nor_numba(recording, tmp_path, capsys, monkeypatch):
    """With the runs kept, a fresh `vibkit links` (run as the `vibkit` script runs it) reads them without importing
    the model's kernels (numba), and reads its netCDF recording with xarray as where dask is not installed."""
    import subprocess
    import sys

    rec, profile = recording
    _links(rec, profile, tmp_path, capsys, monkeypatch)  # keeps the runs in tmp_path
    code = (
        f"import sys\nsys.argv = ['vibkit', 'links', {str(rec)!r}, '--escalator', {str(profile)!r}, '--json']\n"
        "from vibkit.cli import main\nassert main() == 0\n"
        "print('numba' in sys.modules, 'vibkit.analyses.simulation' in sys.modules, file=sys.stderr)\n"
        "print('dask', sys.modules.get('dask', 'absent'), file=sys.stderr)\n"
    )
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path), PYTHONPATH=os.path.dirname(os.path.dirname(vibkit.__file__)))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip().splitlines()[-2:] == ["False False", "dask None"], proc.stderr
