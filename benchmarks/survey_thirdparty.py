"""Regenerate data/thirdparty/SURVEY.md: what vibkit reads from each third-party file with no options.

For every file of data/thirdparty (facts read by hand in expected.json): the reader's rate, time
column, channels and units (``vibkit.read_recording(FILE)``, no options), the verdict against
expected.json (rate within 1 %, same time column, channels and SI units), and unless ``--no-pitch``
``vibkit pitch FILE --speed 0.5 --nominal-pitch 0.13333 --json --channel CH`` on every channel
(none of these files is an escalator: every channel should say ``no link-pass found``).

    python benchmarks/survey_thirdparty.py            # writes data/thirdparty/SURVEY.md
    python benchmarks/survey_thirdparty.py --no-pitch --stdout
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT / "data" / "thirdparty"


def _si(text):
    from vibkit.io.text.units import parse_unit

    u = parse_unit(text.split(" (")[0])
    return text if u is None else u.si


def read_facts(path):
    """(facts text, verdict, channel variable names) of one file read with no options."""
    from vibkit.io import read_recording

    e = json.loads((CORPUS / "expected.json").read_text(encoding="utf-8"))[path.name]
    try:
        ds = read_recording(path)
    except Exception as exc:  # noqa: BLE001 - a survey reports every failure
        return f"read error: {' '.join(str(exc).split())[:160]}", "WRONG: not read", []
    chans, names = {}, []
    for v in ds.data_vars:
        if v == "segment":
            continue
        a = ds[v].attrs
        name = a.get("trace_id") or a.get("source_name") or v
        chans["".join(name.split()) if "trace_id" in a else name] = a["units"]
        names.append(str(v))
    fs = float(ds.attrs["sample_rate_hz"])
    tcol = ds["time"].attrs.get("column")
    facts = f"{fs:.6g} Hz; time={tcol!r}; " + ", ".join(f"{k} [{u}]" for k, u in chans.items())
    if "update_rate_hz" in ds.attrs:
        facts += f"; values held: update rate {ds.attrs['update_rate_hz']:.3g} Hz"
    wrong = []
    if abs(fs / e["sample_rate_hz"] - 1) > 0.01:
        wrong.append(f"rate off by {100 * (fs / e['sample_rate_hz'] - 1):+.1f} %")
    if tcol != e["time_column"]:
        wrong.append(f"time column {tcol!r}")
    if list(chans) != list(e["channels"]):
        wrong.append(f"channels {list(chans)}")
    else:
        bad = [k for k, u in e["channels"].items() if chans[k] != _si(u)]
        if bad:
            wrong.append("units of " + ", ".join(bad))
    return facts, ("right" if not wrong else "WRONG: " + "; ".join(wrong)), names


def expected_text(name):
    e = json.loads((CORPUS / "expected.json").read_text(encoding="utf-8"))[name]
    return f"{e['sample_rate_hz']} Hz; time={e['time_column']!r} ({e['time_unit']}); " + ", ".join(
        f"{k} [{u}]" for k, u in e["channels"].items()
    )


def pitch(path, channel):
    from vibkit.cli import main

    argv = ["pitch", str(path), "--speed", "0.5", "--nominal-pitch", "0.13333", "--json"]
    if channel:
        argv += ["--channel", channel]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    try:
        status = json.loads(out.getvalue()).get("status", "?")
    except ValueError:
        status = "error"
    return f"{channel or '(default)'}: {status} (rc {rc})"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-pitch", action="store_true", help="reader columns only (seconds)")
    ap.add_argument("--stdout", action="store_true", help="print instead of writing SURVEY.md")
    a = ap.parse_args(argv)
    names = sorted(json.loads((CORPUS / "expected.json").read_text(encoding="utf-8")))
    commit = (
        subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
        ).stdout.strip()
        or "?"
    )
    rows, right, pitched, ok_pitch = [], 0, 0, 0
    for name in names:
        path = CORPUS / name
        facts, verdict, chans = read_facts(path)
        right += verdict == "right"
        cells = [name, facts.replace("|", "/"), expected_text(name).replace("|", "/"), verdict.replace("|", "/")]
        if not a.no_pitch:
            res = [pitch(path, ch) for ch in chans] or [pitch(path, None)]
            pitched += 1
            ok_pitch += any(": ok " in r for r in res)
            cells.append("; ".join(res))
        rows.append("| " + " | ".join(cells) + " |")
    head = ["file", "vibkit read (rate; time column; channels [units])", "expected", "read verdict"]
    if not a.no_pitch:
        head.append("pitch per channel (status, exit code)")
    text = [
        f"# Survey: vibkit on the third-party corpus (code at {commit})",
        "",
        "Regenerated by `python benchmarks/survey_thirdparty.py` (reader facts: "
        "`vibkit.read_recording(FILE)` with no options; expected: `expected.json`; units compared in SI, "
        "so `g` in the file is `m/s^2` in vibkit; a column that counts samples is no channel).",
        "",
        f"**Summary: {right} of {len(names)} files read right with no options"
        + (
            ""
            if a.no_pitch
            else f"; {ok_pitch} of {pitched} give a pitch (status `ok`) on at least one channel, where none should"
        )
        + ".**",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ] + rows
    out = "\n".join(text) + "\n"
    if a.stdout:
        print(out)
    else:
        (CORPUS / "SURVEY.md").write_text(out, encoding="utf-8")
        print(f"wrote {CORPUS / 'SURVEY.md'}: {right} of {len(names)} read right")
    return 0


if __name__ == "__main__":
    sys.exit(main())
