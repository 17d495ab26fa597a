"""A stored-like fleet measurement for the fleet's tests, without analysing a recording."""

import datetime as dt

from vibkit.fleet import Measurement

NOMINAL = 0.4 / 3
T0 = dt.datetime(2023, 1, 15, tzinfo=dt.timezone.utc)


def fake(i, unit, years, e, *, s=0.05, quality="ok", replaced=False, nominal=NOMINAL):
    t = T0.timestamp() + years * 365.25 * 86400
    return Measurement(
        id=None,
        unit=unit,
        date_utc=dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z"),
        date_unix_s=t,
        date_source="given",
        speed_m_s=0.5,
        speed_sigma_m_s=0.001,
        nominal_pitch_m=nominal,
        channel="accel",
        fundamental_hz=3.75,
        fundamental_sigma_hz=1e-3,
        pitch_m=nominal * (1 + e / 100),
        pitch_sigma_m=nominal * s / 100,
        elongation_percent=e,
        elongation_sigma_percent=s,
        snr_db=None if i % 5 == 0 else 20.0 + i,
        warnings=("w",) if i % 3 == 0 else (),
        sha256=f"{i:064x}",
        path=f"/visits/r{i}.csv",
        size_bytes=1000 + i,
        vibkit_version="t",
        analysed_utc="2026-11-23T10:00:00Z",
        quality=quality,
        quality_reason="" if quality == "ok" else "given",
        replaced=replaced,
    )
