"""Sweeps (vibkit.sweep.run, `vibkit sweep`): equal to single runs bit for bit, resumable, failures recorded."""

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.cli import main
from vibkit.model.scene import parse_scene
from vibkit.sweep import SweepError, plan_sweep

SW = sys.modules["vibkit.sweep.run"]  # the module (vibkit.sweep is the function)
SP = sys.modules["vibkit.sweep.plan"]  # the plan and the varied scene texts
ST = sys.modules["vibkit.sweep.store"]  # the store and open_sweep

# the no-load forward scene from rest with a stiff P controller (at speed within 0.5 s), 2 s: short; from rest
# the teeth take load at once
SCENE = """
[scene]
name = "sweep-test"
analysis = "forward"

[guide]
tensioner_length = 0.4
lower_landing = 0.8
upper_landing = 0.8
transition_radius = 1.5
incline_angle_deg = 30.0
incline_length = 5.19615

[chain]
link_pitch = 0.13333333333333333
n_rollers = 159

[sprocket]
teeth = 28
base_width = 0.060
tip_width = 0.040
tooth_height = 0.070
mass = 250.62
inertia = 43.78

[run]
duration = 2.0
output_step = 0.005
start = 0.0
initial_speed = 0.0

[effects]
gravity = true
contact = { stiffness = 1.0e6, exponent = 1.5 }
motor = { kp = 6000.0, speed = 0.5 }

[solver]
method = "dopri5"
rtol = 1e-5
atol = 1e-7

[outputs]
variables = ["delta", "link_tension", "contact_force", "closure_residual", "chain_speed"]
"""

PITCHES = (0.1333, 0.1335, 0.1337)
STIFFNESS = (1e5, 1e6, 1e7)
VARY = {"chain.link_pitch": "0.1333:0.1337:3", "effects.contact.stiffness": "1e5,1e6,1e7"}


def _variant(pitch, k):
    return SCENE.replace("link_pitch = 0.13333333333333333", f"link_pitch = {pitch!r}").replace(
        "stiffness = 1.0e6", f"stiffness = {k!r}"
    )


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("sweep") / "scene.toml"
    p.write_text(SCENE)
    return p


@pytest.fixture(scope="module")
def threaded_client():
    """An in-process cluster (2 threads): lets a test count the simulations the workers run."""
    from distributed import Client

    with Client(processes=False, n_workers=2, threads_per_worker=1, dashboard_address=":0") as c:
        yield c


@pytest.fixture(scope="module")
def grid(scene_file, tmp_path_factory):
    """The 3x3 sweep on a 2-process local cluster, streamed to a store."""
    out = tmp_path_factory.mktemp("sweep") / "grid.zarr"
    ds = vibkit.sweep(
        scene_file, VARY, output=out, keep=["delta", "link_tension"], n_workers=2, progress=False, parallel=True
    )
    return ds, out


def test_grid_equals_single_runs_bit_for_bit(grid):
    ds, out = grid
    assert ds["delta"].dims == ("chain.link_pitch", "effects.contact.stiffness", "time")
    np.testing.assert_array_equal(ds["chain.link_pitch"].values, PITCHES)
    assert ds["chain.link_pitch"].attrs["units"] == "m"
    assert (ds["status"].values == 0).all() and ds.attrs["runs_ok"] == 9
    for i, pitch in enumerate(PITCHES):
        for j, k in enumerate(STIFFNESS):
            ref = vibkit.simulate(parse_scene(_variant(pitch, k)), progress=False)
            got = ds.isel({"chain.link_pitch": i, "effects.contact.stiffness": j})
            np.testing.assert_array_equal(got["delta"].values, ref["delta"].values)
            np.testing.assert_array_equal(got["link_tension"].values, ref["link_tension"].values)
            assert float(got["peak_link_tension"]) == float(ref["link_tension"].max())
            assert float(got["closure_residual_max"]) == float(ref["closure_residual"].max()) < 1e-9
            steady = ref["time"] >= 0.5  # the default start-up: a quarter of the run
            d = ref["delta"].where(steady, drop=True).values
            assert float(got["delta_mean"]) == pytest.approx(d.mean(), rel=1e-12)
            assert float(got["delta_ripple"]) == pytest.approx(d.max() - d.min(), rel=1e-12)
            # roller 1's advance along the guide over time is its mean speed, about the motor's 0.5 m/s
            v = ref["chain_speed"].where(steady, drop=True).values.mean()
            assert float(got["link_pass_frequency"]) == pytest.approx(v / pitch, rel=2e-3)
            assert float(got["link_pass_frequency"]) == pytest.approx(0.5 / pitch, rel=0.02)  # 1.5 s of rattle
            # the teeth push the chain up to speed, then rattles within the backlash
            on = ref["contact_force"].values > 0
            assert float(got["contact_episodes"]) == on[0].sum() + (on[1:] & ~on[:-1]).sum() >= 1
            assert 0 < float(got["last_contact_time"]) == ref["time"].values[on.any(axis=1)][-1]
    # the store reads back the same numbers, consolidated, the per-run groups gone
    back = xr.open_zarr(out)
    xr.testing.assert_identical(back["delta"].load(), ds["delta"].load())
    assert not (Path(out) / "runs").exists()


def test_store_time_opens_in_seconds(grid):
    """Plain xarray (default decoding) reads the kept series' time as float seconds, as vibkit wrote it."""
    ds, out = grid
    with xr.open_zarr(out) as plain:
        assert plain["time"].dtype == np.float64 and plain["time"].attrs["units"] == "s"
        np.testing.assert_array_equal(plain["time"].values, ds["time"].values)


def test_rerun_of_a_complete_store_computes_nothing(grid, scene_file):
    ds, out = grid
    again = vibkit.sweep(scene_file, VARY, output=out, keep=["delta", "link_tension"], progress=False)
    assert again.attrs["runs_computed"] == 0
    xr.testing.assert_identical(again["delta"].load(), ds["delta"].load())


def test_interrupted_sweep_resumes_without_recomputing(scene_file, tmp_path, grid, threaded_client, monkeypatch):
    calls = []
    real = SW._simulate

    def counting(scene, duration):
        calls.append((scene.chain.link_pitch, scene.effects["contact"].stiffness))
        return real(scene, duration)

    monkeypatch.setattr(SW, "_simulate", counting)
    out = tmp_path / "resume.zarr"
    part = vibkit.sweep(
        scene_file, VARY, output=out, keep=["delta"], client=threaded_client, progress=False, max_runs=4
    )
    assert len(calls) == 4 and part.attrs["runs_pending"] == 5
    assert (part["status"].values == -1).sum() == 5
    # a run whose data reached the disk but whose done flag did not (killed mid-write) is redone
    runs = sorted((out / "runs").glob("r0*"))
    assert len(runs) == 4
    zattrs = runs[0] / ".zattrs"
    attrs = json.loads(zattrs.read_text())
    attrs.pop("done")
    zattrs.write_text(json.dumps(attrs))
    # a run with a chunk overwritten and one with a chunk deleted are redone too (their checksums say so)
    chunk = sorted((runs[1] / "delta").glob("[0-9]*"))[0]
    chunk.write_bytes(b"\x02\x01garbage" * 8)
    sorted((runs[2] / "delta").glob("[0-9]*"))[0].unlink()
    calls.clear()
    full = vibkit.sweep(scene_file, VARY, output=out, keep=["delta"], client=threaded_client, progress=False)
    assert len(calls) == 9 - 4 + 3 and len(set(calls)) == len(calls)
    assert full.attrs["runs_computed"] == 8 and full.attrs["runs_reused"] == 1
    np.testing.assert_array_equal(full["delta"].values, grid[0]["delta"].values)


def test_a_damaged_complete_store_is_refused_then_recomputed_with_force(grid, scene_file, threaded_client, tmp_path):
    ds, out = grid
    copy = tmp_path / "damaged.zarr"
    shutil.copytree(out, copy)
    sorted((copy / "delta").glob("[0-9]*"))[0].unlink()  # zarr would read it back as fill values
    with pytest.raises(SweepError, match=r"damaged: chunk\(s\) delta/\S+ missing.*--force"):
        vibkit.sweep(
            scene_file, VARY, output=copy, keep=["delta", "link_tension"], client=threaded_client, progress=False
        )
    with pytest.raises(SweepError, match="damaged"):
        ST.open_sweep(copy)
    again = vibkit.sweep(
        scene_file,
        VARY,
        output=copy,
        keep=["delta", "link_tension"],
        client=threaded_client,
        progress=False,
        force=True,
    )
    assert again.attrs["runs_computed"] == 9
    np.testing.assert_array_equal(again["delta"].values, ds["delta"].values)


def test_a_different_sweep_on_the_store_is_refused_unless_forced(grid, scene_file, threaded_client):
    _, out = grid
    other = {"chain.link_pitch": "0.1333:0.1337:2"}
    with pytest.raises(SweepError, match="holds a different sweep"):
        vibkit.sweep(scene_file, other, output=out, client=threaded_client, progress=False)
    ds = vibkit.sweep(scene_file, other, output=out, client=threaded_client, progress=False, force=True)
    assert ds.sizes["chain.link_pitch"] == 2 and ds.attrs["runs_ok"] == 2


def test_not_a_sweep_store_is_never_touched(scene_file, tmp_path):
    target = tmp_path / "mine.zarr"
    target.mkdir()
    (target / "notes.txt").write_text("keep me")
    with pytest.raises(SweepError, match="not a vibkit sweep store"):
        vibkit.sweep(scene_file, VARY, output=target, force=True, progress=False)
    assert (target / "notes.txt").read_text() == "keep me"


def test_failures_are_recorded_and_the_others_complete(scene_file, threaded_client):
    # a negative stiffness is refused by the scene loader; a 1 ns wall-time budget stops the integrator
    ds = vibkit.sweep(
        scene_file,
        {"effects.contact.stiffness": "-1e6,1e6", "solver.max_wall_time": [1e-9, 100.0]},
        client=threaded_client,
        progress=False,
    )
    st = ds["status"].values
    meanings = dict(zip(ds["status"].attrs["flag_values"], ds["status"].attrs["flag_meanings"].split()))
    assert meanings[st[0, 0]] == meanings[st[0, 1]] == "invalid"
    assert "'effects.contact.stiffness' must be positive" in str(ds["error"].values[0, 0])
    assert meanings[st[1, 0]] == "failed" and "wall-time budget" in str(ds["error"].values[1, 0])
    assert np.isnan(ds["delta_mean"].values[1, 0])
    assert meanings[st[1, 1]] == "ok" and ds["error"].values[1, 1] == ""
    assert np.isfinite(ds["delta_mean"].values[1, 1])


def test_monte_carlo_is_reproducible(scene_file, threaded_client):
    vary = {"chain.link_pitch": "0.1330:0.1340", "effects.motor.kp": "300,600,1200"}
    a = plan_sweep(scene_file, vary, samples=50, seed=7)
    b = plan_sweep(scene_file, vary, samples=50, seed=7)
    c = plan_sweep(scene_file, vary, samples=50, seed=8)
    pa = [p["chain.link_pitch"] for p in a.points]
    assert a.points == b.points and pa != [p["chain.link_pitch"] for p in c.points]
    assert all(0.1330 <= v <= 0.1340 for v in pa)
    assert {p["effects.motor.kp"] for p in a.points} == {300.0, 600.0, 1200.0}
    ds = vibkit.sweep(scene_file, vary, samples=3, seed=7, duration=0.5, client=threaded_client, progress=False)
    assert ds["status"].dims == ("sample",)
    assert ds["chain.link_pitch"].dims == ("sample",)
    assert list(ds["chain.link_pitch"].values) == [
        p["chain.link_pitch"] for p in plan_sweep(scene_file, vary, samples=3, seed=7).points
    ]
    assert ds.attrs["seed"] == 7 and (ds["status"].values == 0).all()


@pytest.mark.parametrize(
    "vary, match",
    [
        ({"chain.pitch": "1,2"}, "'chain.pitch'"),
        ({"effects.contact.stifness": "1,2"}, "'effects.contact.stifness'"),
        ({"gear.teeth": "20,28"}, "'gear.teeth'"),
        ({"effects.passengers.mass": "1,2"}, "effects.passengers"),  # the scene has no passengers
        ({"sprocket.teeth": "27.5,28"}, "whole number"),
        ({"chain.link_pitch": "0.13:0.14"}, "A:B:N"),
        ({"chain.link_pitch": "0.1333,0.1333"}, "values repeat"),
    ],
)
def test_bad_keys_and_values_are_named_before_any_run(scene_file, vary, match):
    with pytest.raises(SweepError, match=match):
        plan_sweep(scene_file, vary)


@pytest.mark.slow
def test_cli_json(scene_file, tmp_path, capsys):
    out = tmp_path / "cli.zarr"
    argv = [
        "sweep",
        str(scene_file),
        "--vary",
        "chain.link_pitch=0.1333:0.1337:2",
        "--vary",
        "effects.contact.stiffness=-1,1e6",
        "--duration",
        "1",
        "-o",
        str(out),
        "--workers",
        "2",
        "--json",
        "--quiet",
    ]
    assert main(argv) == 0
    captured = capsys.readouterr()
    d = json.loads(captured.out)
    assert d["schema"] == "vibkit.sweep/1"
    assert d["runs"] == 4 and d["ok"] == 2 and d["invalid"] == 2 and d["complete"]
    assert d["dims"] == {"chain.link_pitch": 2, "effects.contact.stiffness": 2}
    ok = [r for r in d["run_results"] if r["status"] == "ok"]
    assert all(r["link_pass_frequency"] == pytest.approx(0.5 / r["values"]["chain.link_pitch"], rel=0.03) for r in ok)
    assert captured.err == ""
    ds = xr.open_zarr(out)
    assert ds["delta_ripple"].attrs["units"] == "m"
    # the same command again finds the finished store and computes nothing (its folder is no clobber)
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["runs"] == 4 and again["ok"] == 2 and again["complete"]


def test_cli_bad_vary_syntax_is_a_usage_error(scene_file, tmp_path, capsys):
    for bad in (
        "chain.link_pitch",
        "chain.link_pitch=0.13:x:3",
        "chain.link_pitch=0.13:0.14:0",
        "chain.link_pitch=1,,2",
    ):
        with pytest.raises(SystemExit) as exc:
            main(["sweep", str(scene_file), "--vary", bad, "-o", str(tmp_path / "x.zarr")])
        assert exc.value.code == 2
    assert "expected" in capsys.readouterr().err


def test_cli_unknown_key_names_it(scene_file, tmp_path, capsys):
    assert main(["sweep", str(scene_file), "--vary", "chain.pitch=1,2", "-o", str(tmp_path / "x.zarr")]) == 1
    err = capsys.readouterr().err
    assert "chain.pitch" in err and "Traceback" not in err
    assert not (tmp_path / "x.zarr").exists()


class _Stream:
    def __init__(self, tty):
        self.tty, self.text = tty, ""

    def isatty(self):
        return self.tty

    def write(self, s):
        self.text += s

    def flush(self):
        pass


def test_progress_lines_when_piped_a_bar_on_a_terminal_nothing_when_quiet(monkeypatch):
    rec = {"status": 0}
    piped = _Stream(False)
    rep = SW._Report(4, 1, enabled=True, stream=piped, every=0.0)
    for _ in range(3):
        rep.update(rec)
    rep.close()
    lines = piped.text.splitlines()
    assert lines[-1].startswith("sweep: 4/4 runs done (0 failed)") and len(lines) == 3 and "\r" not in piped.text
    monkeypatch.setenv("TERM", "xterm")
    tty = _Stream(True)
    rep = SW._Report(4, 0, enabled=True, stream=tty)
    rep.update(rec)
    rep.close()
    assert "\r" in tty.text and "100.0%" in tty.text
    quiet = _Stream(True)
    rep = SW._Report(4, 0, enabled=False, stream=quiet)
    rep.update(rec)
    rep.close()
    assert quiet.text == ""


@pytest.mark.parametrize(
    "path", sorted((Path(__file__).resolve().parents[2] / "sim").glob("*.toml")), ids=lambda p: p.stem
)
def test_varied_scene_text_reads_back_equal(path):
    """The varied scenes are written back as TOML: every shipped scene survives the round trip."""
    import tomllib

    text = path.read_text()
    data = tomllib.loads(text)
    assert tomllib.loads(SP.to_toml(data)) == data
    a, b = parse_scene(text), parse_scene(SP.varied_text(text, {}))
    assert (a.guide, a.chain, a.sprocket, a.effects, a.outputs, a.sections) == (
        b.guide,
        b.chain,
        b.sprocket,
        b.effects,
        b.outputs,
        b.sections,
    )
    c = parse_scene(SP.varied_text(text, {"chain.link_pitch": 0.1335}))
    assert c.chain.link_pitch == 0.1335
    if data["guide"].get("head_radius") == "sprocket":  # the head follows the sprocket's pitch radius
        assert c.guide.head_radius == c.sprocket.pitch_radius(0.1335) != a.guide.head_radius


@pytest.mark.slow
def test_cli_check_gives_a_converged_flag_per_run(scene_file, tmp_path, capsys):
    """`vibkit sweep --check`: every run's convergence verdict, the same as the single run's."""
    out = tmp_path / "checked.zarr"
    argv = [
        "sweep",
        str(scene_file),
        "--vary",
        "effects.contact.stiffness=1e6,1e7",
        "--duration",
        "1",
        "-o",
        str(out),
        "--workers",
        "2",
        "--json",
        "--quiet",
        "--check",
    ]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["ok"] == 2
    for r in d["run_results"]:
        single = vibkit.simulate(
            parse_scene(
                _variant(0.13333333333333333, r["values"]["effects.contact.stiffness"]).replace(
                    "rtol = 1e-5", "rtol = 1e-5\ncheck = true"
                ),
                "x.toml",
            ),
            duration=1.0,
            progress=False,
        )
        assert r["converged"] is bool(single.attrs["converged"])
    assert set(xr.open_zarr(out)["converged"].values.ravel()) <= {0.0, 1.0}
    with pytest.raises(SweepError, match="forward scenes"):
        vibkit.sweep(
            Path(__file__).resolve().parents[2] / "sim" / "thesis-kinematics.toml",
            {"kinematics.step": "0.001,0.002"},
            check=True,
            progress=False,
        )


def test_a_sweep_whose_every_run_is_refused_exits_1(scene_file, tmp_path, capsys):
    """A stranger's sweep of two chains that cannot close: both runs invalid, and the command exited 0."""
    out = tmp_path / "bad.zarr"
    argv = ["sweep", str(scene_file), "--vary", "effects.contact.stiffness=-1e6,-2e6", "--duration", "1"]
    assert main([*argv, "-o", str(out), "--workers", "1", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "no run could be made (0 failed, 2 invalid)" in err
    assert out.exists()  # the store keeps what each run said


# ------------------------------------------------------------------------------------------ a full disk
def _full_disk_after(monkeypatch, n_ok):
    """The store's writer stores ``n_ok`` runs, then finds the disk full (ENOSPC, as a real writer raises it)."""
    import errno

    real = ST._Store.write_run
    calls = [0]

    def write_run(self, rec):
        calls[0] += 1
        if calls[0] > n_ok:
            raise OSError(errno.ENOSPC, "No space left on device", str(self.path / "runs" / "r000000" / "0"))
        return real(self, rec)

    monkeypatch.setattr(ST._Store, "write_run", write_run)


def _on(client, monkeypatch):
    import contextlib

    monkeypatch.setattr(SW, "dask_client", lambda scheduler=None, n_workers=None: contextlib.nullcontext(client))


def test_full_disk_before_any_run_removes_the_store_this_run_created(
    scene_file, tmp_path, threaded_client, monkeypatch, capsys
):
    _on(threaded_client, monkeypatch)
    _full_disk_after(monkeypatch, 0)
    out = tmp_path / "full.zarr"
    assert main(["sweep", str(scene_file), "--vary", VARY_CLI, "--duration", "0.5", "-o", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert f"{out}: No space left on device (the disk is full;" in err
    assert "held no finished run and was removed" in err
    assert not out.exists() and not list(tmp_path.iterdir())  # no partial store, no temporary folder


def test_full_disk_after_some_runs_keeps_the_store_and_says_how_to_resume(
    scene_file, tmp_path, threaded_client, monkeypatch, capsys
):
    _on(threaded_client, monkeypatch)
    _full_disk_after(monkeypatch, 2)
    out = tmp_path / "full.zarr"
    argv = ["sweep", str(scene_file), "--vary", VARY_CLI, "--duration", "0.5", "-o", str(out), "--quiet", "--json"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert f"{out}: No space left on device (the disk is full; 2 of 4 runs are stored there" in err
    assert err.strip().endswith(f"to resume: vibkit {' '.join(argv)})")
    assert len(list((out / "runs").glob("r0*"))) == 2
    monkeypatch.undo()  # space freed: the command it names resumes from the two stored runs
    _on(threaded_client, monkeypatch)
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["complete"] and d["reused"] == 2 and d["computed"] == 2


def test_full_disk_never_removes_a_store_this_run_did_not_create(scene_file, tmp_path, threaded_client, monkeypatch):
    out = tmp_path / "earlier.zarr"
    vary = {"chain.link_pitch": "0.1333,0.1335"}
    vibkit.sweep(scene_file, vary, output=out, duration=0.5, client=threaded_client, progress=False, max_runs=0)
    assert (out / "runs").is_dir()  # made by an earlier run, no run in it
    _full_disk_after(monkeypatch, 0)
    with pytest.raises(OSError, match="No space left") as e:
        vibkit.sweep(scene_file, vary, output=out, duration=0.5, client=threaded_client, progress=False)
    assert e.value.filename == str(out) and e.value.vibkit_resume and "0 of 2 runs are stored" in e.value.vibkit_note
    assert (out / "runs").is_dir()
    # created by this run, then replaced by another process's store of the same name: not this run's to remove
    other = tmp_path / "raced.zarr"
    real_init = ST._Store.__init__

    def init_then_replaced(self, path, plan, *, force):
        real_init(self, path, plan, force=force)
        shutil.copytree(self.path, tmp_path / "copy.zarr")
        shutil.rmtree(self.path)
        (tmp_path / "copy.zarr").rename(self.path)

    monkeypatch.setattr(ST._Store, "__init__", init_then_replaced)
    with pytest.raises(OSError, match="No space left"):
        vibkit.sweep(scene_file, vary, output=other, duration=0.5, client=threaded_client, progress=False)
    assert (other / "runs").is_dir()


VARY_CLI = "chain.link_pitch=0.1333,0.1335,0.1337,0.1339"
