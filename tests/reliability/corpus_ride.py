"""Reliability cases of ``vibkit ride``, ``pitch`` and ``spectrum``: weighting lists map one to one
onto axes or are refused; every error names the file, in vibkit's words."""

import numpy as np

from corpus import Case

HEAD = "time [s],ax [m/s^2],ay [m/s^2],az [m/s^2]\n"


def _csv(fs, seconds, f=lambda t: 0.3 * np.sin(3.0 * t), gap=None):
    t = np.arange(0.0, seconds, 1.0 / fs)
    x = f(t)
    if gap is not None:
        x[gap[0] : gap[1]] = np.nan
    return HEAD + "\n".join(f"{a:.6f},{b:.6g},{b:.6g},{b + 9.81:.6g}" for a, b in zip(t, x)) + "\n"


STEP = {"step.csv": _csv(200.0, 12.0)}
RIDE = ["ride", "{w}/step.csv", "--segment", "2:10"]

CASES = [
    Case(
        "ride --weighting Wd,Wd,Wk",
        "ride",
        RIDE + ["--weighting", "Wd,Wd,Wk", "--json"],
        files=STEP,
        expect="ok",
        note="x, y: Wd, z: Wk (test_ride_inputs.py checks each axis)",
    ),
    Case(
        "ride --weighting Wb,Wc",
        "ride",
        RIDE + ["--weighting", "Wb,Wc"],
        files=STEP,
        expect_in=("--weighting", "2 weightings for the three axes"),
        expect="usage",
    ),
    Case(
        "ride --weighting x=Wd,x=Wk",
        "ride",
        RIDE + ["--weighting", "x=Wd,x=Wk"],
        files=STEP,
        expect_in=("axis x is given twice",),
        expect="usage",
    ),
    Case(
        "ride --weighting x=Wd,Wk",
        "ride",
        RIDE + ["--weighting", "x=Wd,Wk"],
        files=STEP,
        expect_in=("mix of AXIS=NAME",),
        expect="usage",
    ),
    Case(
        "ride --weighting Wq",
        "ride",
        RIDE + ["--weighting", "Wq"],
        files=STEP,
        expect_in=("unknown weighting 'Wq'",),
        expect="usage",
    ),
    Case(
        "ride, record too short",
        "ride",
        ["ride", "{w}/short.csv"],
        files={"short.csv": _csv(200.0, 0.3)},
        expect_in=("{w}/short.csv", "too short"),
    ),
    Case(
        "ride, segment after the end",
        "ride",
        ["ride", "{w}/short.csv", "--segment", "2:15"],
        files={"short.csv": _csv(200.0, 0.3)},
        expect_in=("{w}/short.csv", "not inside short.csv, which spans 0-"),
    ),
    Case(
        "ride, 10 Hz sample rate",
        "ride",
        ["ride", "{w}/low.csv", "--segment", "2:15"],
        files={"low.csv": _csv(10.0, 20.0)},
        expect_in=("{w}/low.csv", "too low"),
    ),
    Case(
        "ride, no incline",
        "ride",
        ["ride", "{w}/flat.csv"],
        files={"flat.csv": _csv(200.0, 20.0, lambda t: 0 * t)},
        expect_in=("{w}/flat.csv", "no incline"),
    ),
    Case(
        "ride, segment too short",
        "ride",
        ["ride", "{w}/step.csv", "--segment", "0:0.2"],
        files=STEP,
        expect_in=("{w}/step.csv", "too short"),
    ),
    Case(
        "pitch, two rows of 1e300",
        "recording",
        ["pitch", "{w}/two.csv", "--speed", "0.5"],
        files={"two.csv": "time,ax\n0,1e300\n0.01,-1e300\n"},
        expect_in=("{w}/two.csv", "invalid"),
    ),
    Case(
        "spectrum, two rows of 1e300",
        "recording",
        ["spectrum", "{w}/two.csv"],
        files={"two.csv": "time,ax\n0,1e300\n0.01,-1e300\n"},
        expect_in=("{w}/two.csv",),
    ),
    Case(
        "spectrum, 1e300 sine",
        "recording",
        ["spectrum", "{w}/big.csv"],
        files={"big.csv": "time,ax\n" + "".join(f"{i / 100:.2f},{1e300 * np.sin(i / 10):.6g}\n" for i in range(2000))},
        expect_in=("{w}/big.csv",),
    ),
    Case(
        "pitch, two rows",
        "recording",
        ["pitch", "{w}/two.csv", "--speed", "0.5"],
        files={"two.csv": "time,ax\n0,1\n0.01,2\n"},
        expect_in=("{w}/two.csv", "16 valid samples"),
    ),
]
