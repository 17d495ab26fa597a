"""A French header ('Temps (s);Accélération (m/s2)', decimal comma) and numeric dates day/month/year or
month/day/year: the order a field above 12 shows is read, a date that could be either is refused in one
line naming the file, the line and date_order= (--date-order)."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording


def test_french_header_with_decimal_comma(tmp_path):
    p = tmp_path / "mesure.csv"
    t = np.arange(1000) / 200
    a = 9.81 + 0.3 * np.sin(2 * np.pi * 4 * t)
    p.write_text(
        "Temps (s);Accélération (m/s2)\n" + "".join(f"{ti:.3f};{ai:.4f}\n".replace(".", ",") for ti, ai in zip(t, a)),
        encoding="utf-8",
    )
    ds = read_recording(p)
    assert list(ds.data_vars) == ["acceleration"] and ds["acceleration"].attrs["units"] == "m/s^2"
    assert ds["time"].attrs["column"] == "Temps (s)"
    assert ds.attrs["sample_rate_hz"] == pytest.approx(200.0, rel=1e-9) and ds.sizes["time"] == 1000
    np.testing.assert_allclose(ds["acceleration"].values, np.round(a, 4), rtol=0, atol=1e-12)
    assert "decimal comma detected" in ds.attrs["history"]


def stamped(path, first_date, n=50):
    lines = ["Date;acc (g)"]
    for k in range(n):
        lines.append(f"{first_date} 10:00:{k // 10:02d},{k % 10}00;{np.sin(k):.4f}".replace(".", ","))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("date, start", [("25/11/2025", "2025-11-25T10:00:00"), ("11/25/2025", "2025-11-25T10:00:00")])
def test_unambiguous_dates_read_in_their_order(tmp_path, date, start):
    ds = read_recording(stamped(tmp_path / "a.csv", date))
    order = "day/month/year" if date.startswith("25") else "month/day/year"
    assert f"holds {order} timestamps (a field above 12 says the order)" in ds.attrs["history"]
    assert ds.attrs["start_time"].startswith(start)
    np.testing.assert_allclose(ds["time"].values[:3], [0.0, 0.1, 0.2], rtol=0, atol=1e-9)


def test_ambiguous_dates_refused_naming_file_line_and_option(tmp_path, capsys):
    p = stamped(tmp_path / "b.csv", "05/11/2025")
    with pytest.raises(RecordingError) as err:
        read_recording(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}, line 2: dates in column 'Date'") and "pass date_order= (dmy or mdy)" in msg
    rc = main(["spectrum", str(p)])
    cli = capsys.readouterr().err.strip()
    assert rc != 0 and "\n" not in cli and "pass --date-order (dmy or mdy)" in cli
    # given the order, 05/11 is 5 November or 11 May, and a day later is one day later
    lines = p.read_text().splitlines()
    lines[-1] = lines[-1].replace("05/11/2025", "06/11/2025")
    p.write_text("\n".join(lines) + "\n")
    dmy, mdy = read_recording(p, date_order="dmy"), read_recording(p, date_order="mdy")
    assert dmy["time"].values[-1] == pytest.approx(86400 + 4.9, abs=1e-6)  # 6 November
    assert mdy["time"].values[-1] == pytest.approx(31 * 86400 + 4.9, abs=1e-6)  # 11 June
    with pytest.raises(ValueError, match="date_order must be 'dmy'"):
        read_recording(p, date_order="ymd")
