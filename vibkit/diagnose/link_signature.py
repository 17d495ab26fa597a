"""The worn link's signature: how one link of excess pitch changes the per-link map of the tensioner, from two
simulations of the escalator (healthy, and link 1 longer), and how the scene's links are numbered as a recording
numbers them (:func:`link_number_of`), in either direction of travel.

:func:`worn_link_signature` simulates the scene at the recording's speed and sample rate, running the way the
recording's chain ran (:func:`scene_direction`: the scene's motor speed sign, unless told), one loop of settling cut
off, and processes both runs exactly as a recording.  In the runs, roller 1 is at the top of the lower head at
``t = 0`` (the scene's start); running up the links pass in decreasing model number, running down in increasing, so
the run's own numbering is known and its worn link is row 0 of the signature.

Each run's map is kept in memory and on disk, in the user's cache folder (:mod:`vibkit.runtime.user_cache`), keyed
by the scene's text, the run's parameters and the code that made it, and checked when read back.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from ..model.scene import load_scene
from ..runtime.user_cache import (
    code_fingerprint,
    load_blob,
    private_folder,
    private_temp_folder,
    read_checked,
    store_blob,
    write_atomic,
)
from ..signal.linkmap import canonical_phase, link_map, link_pass_phase
from .sensors import SIGNATURES

__all__ = [
    "DIRECTIONS",
    "link_number_of",
    "link_offset",
    "link_phase",
    "profile_scene_file",
    "scene_direction",
    "signature_error",
    "worn_link_signature",
]

#: the ways a chain runs: the steps travel up or down the incline
DIRECTIONS = ("up", "down")
#: tracking bandwidth of the link-pass phase, as a fraction of the link-pass frequency
BANDWIDTH_FRACTION = 1.0 / 40.0
SAMPLES_PER_CYCLE = 16
#: loops (after one of settling) that the signature's runs average over
SIGNATURE_LOOPS = 2
#: the start-up [s] a run discards before its loops; a scene that does not start in steady running (no
#: ``effects.motor.initial_torque``) discards one loop more.  Measured on the driven 408-link metro unit of the
#: tests (1 mm worn link): the signature averaged over loops 1-2 after 5 s, over loops 2-3 and over loops 3-4 differ
#: from each other by 4-9 % (relative RMS; the chain's own loop-to-loop variation), the 5 s start no further from the
#: latest loops (8.1 %) than the one-loop start (9.1 %): the extra loop bought nothing and cost a third of the run
START_UP = 5.0
#: the sensors the model gives a signature for: sensor -> the simulation's output
SENSORS = SIGNATURES  # sensor kind -> the model output its signature is (vibkit.diagnose.sensors)


def link_phase(x, fs, f_lp):
    """The link-pass phase of ``x`` near ``f_lp`` [Hz], by demodulation. [rad]"""
    return link_pass_phase(x, fs, f_lp, bandwidth_hz=f_lp * BANDWIDTH_FRACTION)


def link_number_of(model_link, links_passed, n_links, direction="up"):
    """Number (1-based, in passing order from the link at the sensor) of the scene's link
    ``model_link`` after ``links_passed`` links have passed since the scene's start.

    A link is at the sensor while it goes over the top of the lower head, from the arrival there of one of
    its rollers to the other's.  At the scene's start roller 1 is at the top.  Running up (``direction``
    "up"), rollers arrive in decreasing number (2, 1, n, n - 1 ...): while ``j`` to ``j + 1`` links have
    passed, the link from roller ``(-j - 1) mod n + 1`` to the next is at the sensor (link n, from roller n to
    roller 1, at first) and links pass in decreasing number.  Running down they arrive in increasing number
    (n, 1, 2 ...): the link from roller ``j mod n + 1`` to the next is at the sensor (link 1 at first) and links
    pass in increasing number."""
    j = int(math.floor(links_passed))
    if direction == "down":
        return (model_link - 1 - j) % n_links + 1
    at_sensor = (-1 - j) % n_links  # 0-based model link at the sensor
    return (at_sensor - (model_link - 1)) % n_links + 1


def scene_direction(scene):
    """The way a forward scene's chain runs, "up" or "down": the sign of its motor's set speed, else of its
    initial speed (a scene that sets neither runs up)."""
    speed = scene.effects["motor"].speed if "motor" in scene.effects else scene.run.initial_speed
    return "down" if speed < 0 else "up"


def _starts_steady(scene):
    """Whether a forward scene starts in steady running: its motor's integral set to a running torque
    (``effects.motor.initial_torque``), the teeth carrying the drive from the first sample."""
    return "motor" in scene.effects and scene.effects["motor"].initial_torque != 0.0


def _load(scene_path):

    return load_scene(scene_path)


def _signed(scene_path, speed, direction):
    """The chain speed [m/s] signed by ``direction`` (None: the scene's own, :func:`scene_direction`)."""
    if direction is None:
        direction = scene_direction(_load(scene_path))
    if direction not in DIRECTIONS:
        raise ValueError(f"direction {direction!r}: expected one of {', '.join(DIRECTIONS)}")
    return -abs(float(speed)) if direction == "down" else abs(float(speed))


def _scene_with(scene, *, speed, worn=None):
    chain = scene.chain if worn is None else dataclasses.replace(scene.chain, worn_links=(worn,))
    effects = dict(scene.effects)
    if "motor" in effects:
        effects["motor"] = dataclasses.replace(effects["motor"], speed=float(speed))
    outputs = dict(scene.outputs, variables=tuple(sorted(set(SENSORS.values()) | {"sprocket_angle"})))
    # both runs on the closure walked run by run (exact, and what a worn chain takes): the difference is the
    # worn link's, not the closures'
    return dataclasses.replace(scene, chain=chain, effects=effects, outputs=outputs).with_solver(closure="runs")


@functools.lru_cache(maxsize=32)
def _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops):
    """One run's mean per-link shape (link 1 ``excess`` [m] longer; 0: healthy), the row of its link 1, its links
    and its link offset; ``speed`` signed (negative: the chain runs down).  Kept on disk by the scene's text
    (:func:`_run_key`), so that the next ``vibkit links`` on the same escalator does not simulate it again."""

    scene = load_scene(scene_path)
    if scene.analysis != "forward" or scene.run.start != 0.0:
        raise ValueError(
            f"{scene_path}: the worn link's signature needs a forward scene that starts with roller 1 at the top "
            "of the lower head ([run] start = 0), so that its links can be numbered"
        )
    key = _run_key(scene, sensor, speed, fs, samples_per_cycle, excess, loops)
    kept = _load_run(key, scene.chain.n_rollers, samples_per_cycle)
    if kept is not None:
        return kept
    out = _simulate_run_map(scene, sensor, speed, fs, samples_per_cycle, excess, loops)
    _store_run(key, out)
    return out


def _simulate_run_map(scene, sensor, speed, fs, samples_per_cycle, excess, loops):
    # the model (numba and its kernels) loaded only here, where no kept run serves: a warm `vibkit links` runs without
    from .link_signature_runs import simulate_run

    n = scene.chain.n_rollers
    pitch = scene.chain.link_pitch
    f_lp = abs(speed) / pitch
    settle = START_UP if _starts_steady(scene) else n / f_lp + START_UP
    duration = settle + (loops * n + 3) / f_lp
    worn = None if excess == 0.0 else (1, pitch + excess)
    t, signal, angle = simulate_run(_scene_with(scene, speed=speed, worn=worn), duration, SENSORS[sensor])
    keep = t >= settle
    tx = np.arange(t[keep][0], t[-1], 1.0 / fs)
    x = np.interp(tx, t, signal)
    ph = link_phase(x, fs, f_lp)
    # links passed since the start, on the sprocket; a roller is at the sensor where it is a whole number: where
    # that falls in the signal's cycle (its fundamental's peak is 0) is the offset that numbers the links of the
    # map, and of a recording of this escalator, by the link at the sensor rather than by the signal's cycle
    passed = scene.sprocket.teeth * np.abs(np.interp(tx, t, angle) - angle[0])
    passed /= 2 * np.pi
    cyc = canonical_phase(x, ph) / (2 * np.pi)
    lag = 2 * np.pi * (cyc - passed)
    offset = float(np.angle(np.mean(np.exp(1j * lag))) / (2 * np.pi)) % 1.0
    lmap = link_map(x, fs, ph, n, samples_per_cycle=samples_per_cycle, link_offset=offset)
    # the map's first link as the map counts it (between the link boundaries the offset places in the signal),
    # in links passed on the sprocket: at a start on a boundary the sprocket's count alone may differ by one
    # (5 s at 4.8 Hz is 24 links: every number of a 120-link scene came out one too high)
    whole = round(float(np.mean(cyc - offset - passed)))  # the phase's whole cycles before the sprocket's count
    first = math.floor(cyc[0] - offset) - whole + 0.5
    return lmap.mean_shape, link_number_of(1, first, n, "down" if speed < 0 else "up") - 1, n, offset


@functools.cache
def _code_fingerprint():
    """The sources a run's map depends on (the model, the analyses, the signal layer and this module): a kept run is
    used only by the code that made it."""
    return code_fingerprint(("model", "analyses", "signal"), __file__)


def _run_key(scene, sensor, speed, fs, samples_per_cycle, excess, loops):
    """What a run's map is derived from, as text: the format, vibkit's version and code, numpy's and scipy's versions,
    the scene's text (its SHA-256) and the run's parameters."""
    import hashlib

    import scipy

    from .. import __version__

    return "|".join(
        [
            "link-run 1",
            f"vibkit {__version__} {_code_fingerprint()}",
            f"numpy {np.__version__} scipy {scipy.__version__}",
            f"scene {hashlib.sha256(scene.text.encode()).hexdigest()}",
            f"sensor {sensor} speed {float(speed)!r} fs {float(fs)!r} spc {int(samples_per_cycle)}",
            f"excess {float(excess)!r} loops {int(loops)}",
        ]
    )


def _load_run(key, n, samples_per_cycle):
    """The run kept on disk under ``key`` (:func:`vibkit.runtime.user_cache.load_blob`: the user's own file, this
    key, its payload's hash), when its arrays have the scene's shape; else None."""
    import io

    folder = private_folder("signatures")
    payload = None if folder is None else load_blob(folder, key, ".npz")
    if payload is None:
        return None
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as z:
            shape, meta = np.array(z["shape"], dtype=float), np.array(z["meta"], dtype=float)
    except (OSError, ValueError, KeyError, EOFError):
        return None
    if shape.shape != (n, samples_per_cycle) or meta.shape != (3,) or not np.all(np.isfinite(shape)):
        return None
    row, n_kept, offset = meta
    if int(n_kept) != n or not 0 <= row < n or not 0.0 <= offset < 1.0:
        return None
    return shape, int(row), n, float(offset)


def _store_run(key, run):
    import io

    folder = private_folder("signatures")
    if folder is None:
        return
    shape, row, n, offset = run
    buf = io.BytesIO()
    np.savez(buf, shape=shape, meta=np.array([row, n, offset], dtype=float))
    store_blob(folder, key, buf.getvalue(), ".npz")


def _cache_key(scene_path, sensor, speed, fs, samples_per_cycle, direction=None):
    """The cached runs' key: the same scene, signed speed and rate (rounded) are one run, whoever asks."""
    signed = _signed(scene_path, speed, direction)
    return (str(scene_path), sensor, round(signed, 9), round(float(fs), 6), int(samples_per_cycle))


def _signature_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops):
    healthy, _, n, _ = _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, 0.0, loops)
    worn, row, _, _ = _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops)
    return np.roll(worn - healthy, -row, axis=0), n


def link_offset(scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE, direction=None):
    """Where a roller reaches the sensor in the signal's link-pass cycle of the scene's healthy chain, as a fraction of
    a cycle after the fundamental's peak (:func:`vibkit.signal.linkmap.link_map`'s ``link_offset``): with it a
    recording of this escalator numbers its links from the link at the sensor when it starts (or the marked link),
    as the signature numbers them, wherever the recording starts within a link's passage."""
    key = _cache_key(scene_path, sensor, speed, fs, samples_per_cycle, direction)
    return _run_map_cached(*key, 0.0, SIGNATURE_LOOPS)[3]


def worn_link_signature(
    scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE, excess=1e-3, direction=None
):
    """The change of the per-link map that one link ``excess`` [m] longer makes, row 0 that link.

    Parameters
    ----------
    scene_path : str or Path
        A forward scene of the escalator (its chain, sprocket, guide and motor).
    sensor : {"tensioner"}
    speed : float
        Chain speed of the recording (the scene's motor runs at it, in ``direction``). [m/s]
    fs : float
        The recording's sample rate (the runs are sampled at it). [Hz]
    samples_per_cycle : int, optional
    excess : float, optional
        Excess pitch of the simulated worn link. [m]
    direction : {"up", "down"}, optional
        The way the recording's chain ran (default: the scene's own, :func:`scene_direction`): the runs run that
        way, since the tensioner sees a worn link's wrap in the other order when the chain runs down.

    Returns
    -------
    signature : ndarray (n_links, samples_per_cycle)
    n_links : int
    """
    if sensor not in SENSORS:
        raise ValueError(f"sensor {sensor!r}: the model gives a worn link's signature for {', '.join(SENSORS)} only")
    return _signature_cached(
        *_cache_key(scene_path, sensor, speed, fs, samples_per_cycle, direction), float(excess), SIGNATURE_LOOPS
    )


def signature_error(
    scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE, excess=1e-3, direction=None
):
    """The signature's relative error, as the model shows it: ``|S(e / 2) / (e / 2) - S(e) / e| / |S(e) / e|``,
    ``S(e)`` the signature of a link ``e`` longer (each without the mean over its links, as the scan fits it).
    A linear, reproducible signature gives 0; the study's 159-link scene at 0.5 m/s gives 0.15 at 1 mm."""
    key = _cache_key(scene_path, sensor, speed, fs, samples_per_cycle, direction)
    full, _ = _signature_cached(*key, float(excess), SIGNATURE_LOOPS)
    half, _ = _signature_cached(*key, float(excess) / 2.0, SIGNATURE_LOOPS)
    full = (full - full.mean(axis=0)) / float(excess)
    half = (half - half.mean(axis=0)) / (float(excess) / 2.0)
    return float(np.sqrt(np.sum((half - full) ** 2) / np.sum(full * full)))


def profile_scene_file(profile):
    """An escalator profile's forward scene as a file (the signature is simulated from a scene file): kept in the
    user's cache folder (``$XDG_CACHE_HOME/vibkit/scenes``, else ``~/.cache/vibkit/scenes``, 0700) under the
    SHA-256 of its text, and used again only when the file there is the user's own regular file holding exactly that
    text (anything else is replaced); where the cache folder cannot be used, in a private temporary folder of this
    process (:mod:`vibkit.runtime.user_cache`)."""
    import hashlib

    data = profile.scene_text("forward").encode("utf-8")
    name = f"profile-{hashlib.sha256(data).hexdigest()[:40]}.toml"
    folder = private_folder("scenes")
    if folder is not None and (read_checked(folder, name) == data or write_atomic(folder, name, data)):
        return str(folder / name)
    folder = private_temp_folder("scenes")
    if read_checked(folder, name) != data and not write_atomic(folder, name, data):
        raise OSError(f"cannot write the profile's scene into {folder}")
    return str(folder / name)
