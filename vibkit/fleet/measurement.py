"""One measurement: the analysis of a recording (pitch, elongation, quality, provenance) as a record."""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
import os
from dataclasses import asdict, dataclass

import vibkit
from vibkit.diagnose.channels import estimate_channels
from vibkit.diagnose.settings import resolve_settings
from vibkit.io import read_recording

from .dates import _iso, parse_date
from .errors import FleetError
from .inputs import check_inputs
from .quality import measurement_quality

__all__ = ["Measurement", "analyse_recording"]


@dataclass(frozen=True)
class Measurement:
    """One stored measurement (a row of the database).  Lengths [m], speeds [m/s], elongation [%].

    ``quality`` is ``"ok"``, ``"inconclusive"`` or ``"implausible"`` (:mod:`vibkit.fleet.quality`;
    ``quality_reason`` says why); only ``"ok"`` measurements enter a trend.  ``replaced``: the chain was
    replaced before this measurement, which starts a new trend segment.  ``speed_sigma_m_s`` None means
    the speed's uncertainty was not stated (``fleet add`` without ``--speed-uncertainty``, a catalogue
    without ``speed_sigma_m_s``): ``pitch_sigma_m`` and ``elongation_sigma_percent`` then hold the
    frequency's part only, and :meth:`as_reported` gives them as null.  0 is a stated sigma: an exact speed.
    """

    id: int | None
    unit: str
    date_utc: str
    date_unix_s: float
    date_source: str
    speed_m_s: float
    speed_sigma_m_s: float | None
    nominal_pitch_m: float
    channel: str
    fundamental_hz: float
    fundamental_sigma_hz: float
    pitch_m: float
    pitch_sigma_m: float
    elongation_percent: float
    elongation_sigma_percent: float
    snr_db: float | None
    warnings: tuple
    sha256: str
    path: str
    size_bytes: int
    vibkit_version: str
    analysed_utc: str
    quality: str = "ok"
    quality_reason: str = ""
    replaced: bool = False

    @property
    def speed_sigma_stated(self) -> bool:
        """Whether the speed's uncertainty was stated (None: not stated; 0: stated, an exact speed)."""
        return self.speed_sigma_m_s is not None

    def as_dict(self) -> dict:
        """Every field as stored (``Measurement(**m.as_dict())`` is ``m``)."""
        d = asdict(self)
        d["warnings"] = list(self.warnings)
        return d

    def as_reported(self) -> dict:
        """JSON-ready dict for users (``fleet add --json``): :meth:`as_dict`, but without a stated speed
        uncertainty the speed's, the pitch's and the elongation's sigmas are null, with the reason, and the
        frequency's part under ``*_frequency_only``."""
        d = self.as_dict()
        if not self.speed_sigma_stated:
            d.update(
                speed_sigma_m_s=None,
                pitch_sigma_m=None,
                elongation_sigma_percent=None,
                pitch_sigma_frequency_only_m=self.pitch_sigma_m,
                elongation_sigma_frequency_only_percent=self.elongation_sigma_percent,
                uncertainty="speed uncertainty not stated: the pitch's and the elongation's sigmas are unknown "
                "(the *_frequency_only keys give the frequency's part, a lower bound)",
            )
        return d


def _file_sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def analyse_recording(
    path,
    *,
    unit,
    speed,
    speed_sigma=None,
    nominal_pitch,
    date=None,
    channel=None,
    replaced=False,
    date_source="given",
    read_options=None,
    recording=None,
    n_links=None,
    profile=None,
    segment=None,
):
    """Read and analyse one recording; the :class:`Measurement` it gives (not stored, ``id`` None).

    Parameters
    ----------
    path : str or os.PathLike
        The recording (any format :func:`vibkit.read_recording` reads).
    unit : str
        Escalator identifier.
    speed, speed_sigma : float
        Chain speed and its standard deviation [m/s]; ``speed_sigma`` None: not stated (stored as such), 0: an
        exact speed.
    nominal_pitch : float
        Nominal link pitch. [m]
    date : str or datetime, optional
        Measurement date (ISO 8601); default the recording's start time.
    channel : str, optional
        The channel to analyse; default every vibration channel, the numbers from the one with the smallest
        sigma once the others agree (:func:`vibkit.diagnose.channels.estimate_channels`, as ``vibkit pitch``).
    read_options : dict, optional
        More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).
    n_links : int, optional
        Links in the chain: a worn link's once-per-loop pattern is then not read as a wander
        (:func:`vibkit.diagnose.pitch.estimate_pitch`).
    profile : vibkit.model.profile.Profile, optional
        The unit's escalator profile: its sprocket's teeth, links per step, search band around its link pass and
        sensors are the analysis's, as ``vibkit pitch --escalator`` takes them
        (:func:`vibkit.diagnose.settings.resolve_settings`; without one, those the recording states, else 28 and 3).
    replaced : bool
        The chain was replaced since the unit's previous measurement (a new trend segment starts).
    date_source : str
        Where ``date`` came from (stored as ``date_source``; e.g. ``"file name"``).
    recording : xarray.Dataset, optional
        The file already read by :func:`vibkit.read_recording` (with ``read_options`` and ``channel``): it is not
        read again.
    segment : (float, float), optional
        The part of the file ``recording`` is [s] (:func:`vibkit.fleet.link_scan.measure_with_links` cuts it): the
        run's settings record it.

    The measurement carries its quality flag (:func:`vibkit.fleet.quality.measurement_quality`):
    implausible and inconclusive ones are stored flagged and left out of trends.

    Raises
    ------
    FleetError
        No date (neither given nor in the recording), no link-pass found in the recording, or its channels
        disagree (two periodicities, not one chain).
    RecordingError, ValueError
        The file cannot be read, or an option is invalid.
    """
    # every input checked before the recording is read
    given = check_inputs(unit=unit, speed=speed, speed_sigma=speed_sigma, nominal_pitch=nominal_pitch, date=date)
    unit = str(unit).strip()
    if nominal_pitch is None:
        raise FleetError(f"nominal_pitch must be a length in 0.05-0.3 m, got {nominal_pitch!r}")
    spath = os.fspath(path)
    rec = recording if recording is not None else read_recording(spath, **{**(read_options or {}), "channel": channel})
    if given is not None:
        d, source = given, str(date_source)
    else:
        start = rec.attrs.get("start_time")
        if start is None:
            raise FleetError(
                f"{spath}: the recording has no start time; give the measurement date "
                "(--date, or the catalogue's date column) as ISO 8601, e.g. 2026-11-23"
            )
        try:
            d = parse_date(start, what="the recording's start time", ambiguous_ok=True)
        except FleetError as exc:
            raise FleetError(
                f"{spath}: {exc}; give the measurement date (--date, or the catalogue's date column)"
            ) from None
        source = "recording start time"
    try:  # every vibration channel (or the one asked for), as `vibkit pitch` decides; a sigma of None is "not stated"
        # the run's settings as every command resolves them (the profile's teeth, links per step, band, sensors)
        settings = resolve_settings(
            rec,
            speed=speed,
            speed_sigma=speed_sigma,
            nominal_pitch=nominal_pitch,
            n_links=n_links,
            profile=profile,
            segment=segment,
        )
        res = estimate_channels(
            rec,
            speed=settings.speed.value,
            speed_sigma=settings.speed.sigma,
            channel=channel,
            band=settings.band,
            nominal_pitch=settings.nominal_pitch,
            limits_percent=settings.limits,
            n_links=settings.n_links,
            teeth=settings.teeth,
            links_per_step=settings.links_per_step,
            sensors=settings.sensors_by_channel,
        )
    except ValueError as exc:
        raise FleetError(f"{spath}: {' '.join(str(exc).split())}") from None
    if res.best is None:  # no link pass on any channel, an implausible one, or channels that disagree
        raise FleetError(f"{spath}: {res.status}: {res.reason}; nothing stored")
    est = res.best
    snr = float(est.snr_db) if math.isfinite(est.snr_db) else None
    rel_speed = (
        100.0 * float(speed_sigma) / float(speed) if speed_sigma and speed and float(speed) > 0 else None
    )  # [%] of the speed: where it makes the sigma, the advice is to measure the speed
    quality, why = measurement_quality(
        est.elongation_percent,
        est.elongation_sigma_percent,
        decision=getattr(est, "decision", None),
        speed_sigma_percent=rel_speed,
    )
    return Measurement(
        id=None,
        unit=unit,
        date_utc=_iso(d),
        date_unix_s=d.timestamp(),
        date_source=source,
        speed_m_s=float(est.speed_m_s),
        speed_sigma_m_s=None if est.speed_sigma_m_s is None else float(est.speed_sigma_m_s),
        nominal_pitch_m=float(est.nominal_pitch_m),
        channel=str(est.channel),
        fundamental_hz=float(est.fundamental_hz),
        fundamental_sigma_hz=float(est.fundamental_sigma_hz),
        pitch_m=float(est.pitch_m),
        pitch_sigma_m=float(est.pitch_sigma_m),
        elongation_percent=float(est.elongation_percent),
        elongation_sigma_percent=float(est.elongation_sigma_percent),
        snr_db=snr,
        warnings=tuple(est.warnings),
        sha256=str(rec.attrs["sha256"]),
        path=os.path.abspath(spath),
        size_bytes=os.path.getsize(spath),
        vibkit_version=vibkit.__version__,
        analysed_utc=_iso(_dt.datetime.now(_dt.timezone.utc)),
        quality=quality,
        quality_reason=why,
        replaced=bool(replaced),
    )
