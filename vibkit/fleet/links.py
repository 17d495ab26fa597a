"""Worn links across visits: the link scan stored with each measurement, and which link came back worse.

Each measurement of the fleet may carry the link scan of its recording (:func:`vibkit.diagnose.links.find_worn_links`):
:class:`LinkScan`, its status (``ok``, ``inconclusive``, ``too few loops``, ``failed``, ``not run``), so that a visit
without flagged links is told apart from a visit whose links were not scanned, and the links it flagged
(:class:`FlaggedLink`: number, excess pitch and its sigma, the loops that show it).

A link number names a physical link only when the recording counts from a marked link (``marker_s``: when a link
marked with paint or a tag passed the sensor): without a marker, link 1 is whichever link was at the sensor when the
recording started, a different one at every visit, and the numbers of two visits cannot be matched.
:func:`links_history` therefore compares visits only when both count from the marked link: a link flagged now with a
larger excess than at the previous marked visit, by more than ``coverage_sigma`` (2) combined sigmas, is ``worse``;
one flagged now and not then is ``new``.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field, replace

from ..diagnose.rounding import fmt_pm, fmt_value
from .schema import LINK_STATUSES

__all__ = [
    "FlaggedLink",
    "LinkHistory",
    "LinkScan",
    "LinkVisit",
    "UnitLinks",
    "links_history",
    "read_link_scans",
    "write_link_scan",
]

#: the reason of a measurement stored before vibkit kept link scans (schema 2 and older)
BEFORE_LINK_SCANS = "stored before the fleet kept link scans"
#: the reason of a measurement stored without a link scan (fleet add; a scan without the number of links says so)
NOT_SCANNED = "the links were not scanned (vibkit fleet scan scans them when it knows the number of links)"


def _num(v):
    return None if v is None else float(v)


@dataclass(frozen=True)
class FlaggedLink:
    """One link a scan flagged.  ``link`` 1-based, counted as the scan's :attr:`LinkScan.numbering` says;
    ``excess_pitch_m`` and ``sigma_m`` [m] (None where the signal gives none: without the escalator's scene a
    deviating level gives no pitch); ``loops``: the 1-based loops whose own fit shows it; ``statistic`` its |t|;
    ``feature`` what deviates (``signature``, ``level``, ``duration``); ``alternatives``: the other numbers of a link
    the recording cannot place uniquely (its signature fits nearly as well there), empty when ``link`` is the one
    number."""

    link: int
    excess_pitch_m: float | None
    sigma_m: float | None
    loops: tuple = ()
    statistic: float | None = None
    feature: str = ""
    alternatives: tuple = ()

    @property
    def numbers(self) -> tuple:
        """The numbers the flag may be: ``link`` first, then its alternatives."""
        return (self.link, *self.alternatives)

    @property
    def label(self) -> str:
        """``"55"``, or ``"55 or 10"`` for an ambiguous flag."""
        return " or ".join(str(n) for n in self.numbers)

    def as_dict(self):
        return {
            "link": self.link,
            "alternatives": list(self.alternatives),
            "excess_pitch_m": self.excess_pitch_m,
            "sigma_m": self.sigma_m,
            "loops": list(self.loops),
            "statistic": self.statistic,
            "feature": self.feature,
        }


@dataclass(frozen=True)
class LinkScan:
    """The link scan of one measurement (see the module docstring).

    ``status``: ``ok`` (scanned: ``flagged`` holds what it found, maybe nothing), ``inconclusive`` (deviations that
    no link number can be given for), ``too few loops`` (the recording covers fewer than two loops), ``failed``
    (``reason`` names the error), ``not run`` (``reason`` says why: no number of links, or stored before scans
    were kept).  ``marker_s`` [s]: the time the marked link passed the sensor (link 1), None when the numbers count
    from the link at the sensor at the recording's start.
    """

    status: str
    reason: str = ""
    n_links: int | None = None
    loops: int | None = None
    marker_s: float | None = None
    method: str = ""
    false_alarm: float | None = None
    flagged: tuple = ()
    measurement_id: int | None = None
    #: what was done to the stored numbers on reading them (:data:`RENUMBERED`), else empty
    note: str = ""

    def __post_init__(self):
        if self.status not in LINK_STATUSES:
            raise ValueError(f"link scan status {self.status!r}: expected one of {', '.join(LINK_STATUSES)}")

    @classmethod
    def not_run(cls, reason, **kw):
        return cls("not run", reason=str(reason), **kw)

    @classmethod
    def from_result(cls, res):
        """From a :class:`vibkit.diagnose.links.LinksResult` (its ``*_mm`` in metres here)."""
        flagged = tuple(
            FlaggedLink(
                link=int(f["link"]),
                excess_pitch_m=None if f.get("excess_pitch_mm") is None else 1e-3 * float(f["excess_pitch_mm"]),
                sigma_m=None if f.get("sigma_mm") is None else 1e-3 * float(f["sigma_mm"]),
                loops=tuple(int(i) for i in f.get("loops", ())),
                statistic=_num(f.get("t")),
                feature=str(f.get("feature", "signature")),
                alternatives=tuple(int(i) for i in f.get("alternatives", ())),
            )
            for f in res.flagged
        )
        return cls(
            status="ok" if res.status == "ok" else "inconclusive",
            reason=res.reason,
            n_links=int(res.n_links),
            loops=int(res.loops),
            marker_s=_num(res.marker_s),
            method=res.method,
            false_alarm=_num(res.false_alarm),
            flagged=flagged,
        )

    @property
    def scanned(self) -> bool:
        """Whether the links were scanned and numbered (status ``ok``)."""
        return self.status == "ok"

    @property
    def numbering(self) -> str:
        """What link 1 is: ``"marker"`` (the marked link) or ``"start"`` (the link at the sensor at the start)."""
        return "marker" if self.marker_s is not None else "start"

    def flag(self, link):
        return next((f for f in self.flagged if f.link == link), None)

    def as_dict(self):
        return {
            "status": self.status,
            "reason": self.reason,
            "n_links": self.n_links,
            "loops": self.loops,
            "marker_s": self.marker_s,
            "numbering": self.numbering,
            "method": self.method,
            "false_alarm": self.false_alarm,
            "flagged": [f.as_dict() for f in self.flagged],
            "note": self.note,
        }


# ------------------------------------------------------------------------------------------ storage
_SCAN_COLS = ("status", "reason", "n_links", "loops", "marker_s", "method", "false_alarm")
_FLAG_COLS = ("link", "excess_pitch_m", "sigma_m", "statistic", "feature", "loops", "alternatives")


def write_link_scan(store, measurement_id, scan: LinkScan):
    """Insert the link scan of a stored measurement (inside the store's write transaction)."""
    cols = ("measurement_id",) + _SCAN_COLS
    vals = [int(measurement_id)] + [getattr(scan, c) for c in _SCAN_COLS]
    store.execute(store.q(f"INSERT INTO link_scan ({', '.join(cols)}) VALUES ({', '.join('?' * len(cols))})"), vals)
    fcols = ("measurement_id",) + _FLAG_COLS
    for f in scan.flagged:
        store.execute(
            store.q(f"INSERT INTO flagged_link ({', '.join(fcols)}) VALUES ({', '.join('?' * len(fcols))})"),
            [
                int(measurement_id),
                f.link,
                f.excess_pitch_m,
                f.sigma_m,
                f.statistic,
                f.feature,
                json.dumps(list(f.loops)),
                json.dumps([int(i) for i in f.alternatives]),
            ],
        )


def read_link_scans(store, unit=None) -> dict:
    """``{measurement id: LinkScan}`` of the stored scans (of one unit if given); a store without the link tables
    (schema 2 or older read without upgrading it) has none; a schema-3 one read as it is, no alternatives."""
    if not getattr(store, "has_link_tables", True):
        return {}
    fcols = _FLAG_COLS if getattr(store, "has_link_alternatives", True) else _FLAG_COLS[:-1]
    where, args = ("WHERE m.unit = ?", (str(unit),)) if unit is not None else ("", ())
    scans = {}
    for r in store.execute(
        store.q(
            f"SELECT s.measurement_id, {', '.join('s.' + c for c in _SCAN_COLS)}, m.vibkit_version FROM link_scan s "
            f"JOIN measurement m ON m.id = s.measurement_id {where}"
        ),
        args,
    ).fetchall():
        d = dict(zip(("measurement_id",) + _SCAN_COLS + ("vibkit_version",), r))
        scans[int(r[0])] = d
    flags = {}
    for r in store.execute(
        store.q(
            f"SELECT f.measurement_id, {', '.join('f.' + c for c in fcols)} FROM flagged_link f "
            f"JOIN measurement m ON m.id = f.measurement_id {where} ORDER BY f.measurement_id, f.link"
        ),
        args,
    ).fetchall():
        d = dict(zip(fcols, r[1:]))
        flags.setdefault(int(r[0]), []).append(
            FlaggedLink(
                link=int(d["link"]),
                excess_pitch_m=_num(d["excess_pitch_m"]),
                sigma_m=_num(d["sigma_m"]),
                loops=tuple(json.loads(d["loops"] or "[]")),
                statistic=_num(d["statistic"]),
                feature=d["feature"],
                alternatives=tuple(int(i) for i in json.loads(d.get("alternatives") or "[]")),
            )
        )
    out = {}
    for mid, d in scans.items():
        n = None if d["n_links"] is None else int(d["n_links"])
        flagged, note = tuple(flags.get(mid, ())), ""
        if n and flagged and counted_two_high(d["vibkit_version"], d["method"]):
            flagged = tuple(_renumbered(f, n) for f in flagged)
            note = RENUMBERED.format(version=d["vibkit_version"])
        out[mid] = LinkScan(
            status=d["status"],
            reason=d["reason"],
            n_links=n,
            loops=None if d["loops"] is None else int(d["loops"]),
            marker_s=_num(d["marker_s"]),
            method=d["method"],
            false_alarm=_num(d["false_alarm"]),
            flagged=flagged,
            measurement_id=mid,
            note=note,
        )
    return out


#: before 0.4.5 a scan with the scene's signature numbered every link two too high (the link going over the top of
#: the lower head was counted as the one two ahead of it): such stored numbers are read two lower
RENUMBERED = (
    "numbers stored by vibkit {version} read two lower: before 0.4.5 a scan with the scene's signature numbered "
    "every link two too high"
)


def counted_two_high(version, method) -> bool:
    """Whether a stored scan's numbers are two too high: made with the scene's signature by vibkit before 0.4.5."""
    m = re.match(r"(\d+)\.(\d+)\.(\d+)", str(version or ""))
    return bool(m) and tuple(map(int, m.groups())) < (0, 4, 5) and str(method).startswith("worn-link signature")


def _renumbered(f, n):
    """Flag ``f`` with its number and alternatives two lower, round a chain of ``n`` links."""

    def lower(k):
        return (int(k) - 3) % n + 1

    return replace(f, link=lower(f.link), alternatives=tuple(lower(k) for k in f.alternatives))


# ------------------------------------------------------------------------------------------ history
@dataclass(frozen=True)
class LinkVisit:
    """One visit of one link: whether that visit's scan flagged it, as which number(s) (``link`` and its
    ``alternatives``: the flag of that visit), and with what excess pitch [m]."""

    measurement_id: int
    date_utc: str
    flagged: bool
    excess_pitch_m: float | None = None
    sigma_m: float | None = None
    loops: tuple = ()
    link: int | None = None
    alternatives: tuple = ()

    @property
    def numbers(self) -> tuple:
        return () if self.link is None else (self.link, *self.alternatives)

    @property
    def label(self) -> str:
        return " or ".join(str(n) for n in self.numbers)

    def as_dict(self):
        return {
            "measurement_id": self.measurement_id,
            "date_utc": self.date_utc,
            "flagged": self.flagged,
            "link": self.link,
            "alternatives": list(self.alternatives),
            "excess_pitch_m": self.excess_pitch_m,
            "sigma_m": self.sigma_m,
            "loops": list(self.loops),
        }


@dataclass(frozen=True)
class LinkHistory:
    """One flagged link over the visits it can be compared across: ``link`` the number its latest flag gives best,
    ``alternatives`` the other numbers that flag may be (the recording cannot tell which: "55 or 10").  A visit's
    flag is the same link when it shares a number with the later flag: a link flagged as "55 or 10" and then as
    "10" is one link.

    ``verdict`` for the latest scan against the previous one counting from the marked link: ``worse`` (the excess
    grew by more than ``coverage_sigma`` combined sigmas), ``new`` (flagged now, none of its numbers then),
    ``unchanged``, ``smaller``, ``flagged again`` (no sigma or no excess to compare), ``not flagged now``;
    ``flagged`` when there is no earlier visit to compare with, ``unmatched`` when the latest scan has no marker
    (its number names no link).  ``detail`` says it in words, and says when a flag is ambiguous."""

    link: int
    verdict: str
    detail: str
    visits: tuple
    alternatives: tuple = ()

    @property
    def label(self) -> str:
        """``"55"``, or ``"55 or 10"`` when the latest flag is ambiguous."""
        return " or ".join(str(n) for n in (self.link, *self.alternatives))

    def as_dict(self):
        return {
            "link": self.link,
            "alternatives": list(self.alternatives),
            "verdict": self.verdict,
            "detail": self.detail,
            "visits": [v.as_dict() for v in self.visits],
        }


@dataclass(frozen=True)
class UnitLinks:
    """What :func:`links_history` says of one unit: every visit with its scan (``(Measurement, LinkScan)``, by
    date), whether the latest scan can be compared with an earlier one (``comparable``), a ``statement`` saying so
    in words, and the links (``links``: :class:`LinkHistory`, worse first)."""

    unit: str
    visits: tuple
    comparable: bool
    statement: str
    links: tuple = field(default_factory=tuple)
    coverage_sigma: float = 2.0

    @property
    def scanned(self) -> bool:
        return any(s.scanned for _, s in self.visits)

    def as_dict(self):
        return {
            "unit": self.unit,
            "comparable": self.comparable,
            "statement": self.statement,
            "coverage_sigma": self.coverage_sigma,
            "visits": [
                {"measurement_id": m.id, "date_utc": m.date_utc, "path": m.path, **s.as_dict()} for m, s in self.visits
            ],
            "links": [h.as_dict() for h in self.links],
        }


_ORDER = {"worse": 0, "new": 1, "flagged again": 2, "unchanged": 3, "smaller": 4, "not flagged now": 5}


def _visit(m, f):
    """The LinkVisit of measurement ``m`` whose scan flagged ``f`` (None: not flagged on that visit)."""
    if f is None:
        return LinkVisit(m.id, m.date_utc, False)
    return LinkVisit(m.id, m.date_utc, True, f.excess_pitch_m, f.sigma_m, f.loops, f.link, tuple(f.alternatives))


def _mm(v, s=None, *, pm=False):
    """An excess pitch [m] in mm, to two significant digits of its sigma (the one rule of every +-; 0.01 mm without
    one), the sigma after it with ``pm``."""
    if v is None:
        return "-"
    if not s:
        return f"{1e3 * v:+.2f} mm"
    return fmt_pm(1e3 * v, 1e3 * s, "mm", sign=True) if pm else f"{fmt_value(1e3 * v, 1e3 * s, sign=True)} mm"


def _flag_words(f):
    if f.excess_pitch_m is None:
        return f"a deviating {f.feature or 'cycle'} (no excess pitch)"
    return _mm(f.excess_pitch_m, f.sigma_m, pm=True)


def _ambiguous(v):
    """Words for a flag (FlaggedLink or LinkVisit) that names more than one number; empty for one number."""
    if len(v.numbers) < 2:
        return ""
    others = " or ".join(str(n) for n in v.numbers[1:])
    return f"; ambiguous: link {v.numbers[0]} or {others}, the recording cannot tell which (look at both)"


def _as(before, now):
    """' as 55 or 10' when the earlier flag named other numbers than the later one."""
    return f" as {before.label}" if before.numbers != now.numbers else ""


def _compare(now, before, k):
    """Verdict and its words for a link flagged ``now`` against its visit ``before`` (LinkVisits)."""
    if not before.flagged:
        where = "not" if len(now.numbers) < 2 else "none of them"
        return "new", f"flagged now ({_mm(now.excess_pitch_m, now.sigma_m)}), {where} on {before.date_utc[:10]}"
    was = f"{before.date_utc[:10]}{_as(before, now)}"
    if None in (now.excess_pitch_m, before.excess_pitch_m, now.sigma_m, before.sigma_m):
        return "flagged again", f"flagged on {was} too; no excess pitch with a sigma to compare"
    diff = now.excess_pitch_m - before.excess_pitch_m
    comb = math.hypot(now.sigma_m, before.sigma_m)
    words = (
        f"{_mm(before.excess_pitch_m, before.sigma_m)} on {was} -> {_mm(now.excess_pitch_m, now.sigma_m)}: "
        f"{_mm(diff, comb, pm=True)}"
    )
    if diff > k * comb:
        return "worse", words
    if diff < -k * comb:
        return "smaller", words
    return "unchanged", words + f" (within {k:g} sigma)"


#: when an earlier flag ``g`` is the link a later flag ``ref`` flagged, in order of preference: the same best number;
#: one names the other's best number; any shared number
_SAME_LINK = (
    lambda g, ref: g.link == ref.link,
    lambda g, ref: ref.link in g.numbers or g.link in ref.numbers,
    lambda g, ref: bool(set(g.numbers) & set(ref.numbers)),
)


def _follow(marked):
    """The flags of the marked visits grouped by link, newest visit first: a list per link of each visit's flag
    (None: not flagged then).  An earlier flag joins the link of the nearest later flag it shares a number with,
    the closer matches (:data:`_SAME_LINK`) paired first over all links."""
    groups = []
    for i in reversed(range(len(marked))):
        free = list(marked[i][1].flagged)
        for same in _SAME_LINK:
            for g in groups:
                if g[i] is not None:
                    continue
                ref = next(f for f in g[i + 1 :] if f is not None)
                hit = next((f for f in free if same(f, ref)), None)
                if hit is not None:
                    g[i] = hit
                    free.remove(hit)
        for f in free:
            g = [None] * len(marked)
            g[i] = f
            groups.append(g)
    return groups


def links_history(db, unit, *, coverage_sigma=2.0) -> UnitLinks:
    """The link scans of one unit's visits and which links came back worse.

    Parameters
    ----------
    db : FleetDB
    unit : str
    coverage_sigma : float
        A link is ``worse`` when its excess pitch grew by more than this many combined standard deviations.

    Returns
    -------
    UnitLinks
        The latest scanned visit is compared with the previous one only when both count their links from the
        marked link (``marker_s``) with the same number of links; otherwise ``comparable`` is False and
        ``statement`` says why (without a marker a link number names no physical link).
    """
    k = float(coverage_sigma)
    ms = db.measurements(unit)
    scans = db.link_scans(unit)
    visits = tuple((m, scans.get(m.id) or LinkScan.not_run(BEFORE_LINK_SCANS, measurement_id=m.id)) for m in ms)
    out = _history(visits, str(unit), k)
    done = [m for m, s in visits if s.scanned]
    if done and visits[-1][0].id != done[-1].id:  # the latest visit was not scanned: say so
        m, s = visits[-1]
        note = f" (the latest visit, {m.date_utc[:10]}, has no link scan: {s.status}: {s.reason})"
        out = UnitLinks(out.unit, out.visits, out.comparable, out.statement + note, out.links, k)
    return out


def _history(visits, unit, k):
    done = [(m, s) for m, s in visits if s.scanned]
    if not done:
        why = visits[-1][1].reason if visits else "no measurement"
        last = f" (latest: {visits[-1][1].status}: {why})" if visits else ""
        return UnitLinks(str(unit), visits, False, f"no visit of unit {unit} has a link scan{last}", (), k)
    m_now, s_now = done[-1]
    day = m_now.date_utc[:10]
    if s_now.marker_s is None:
        links = tuple(
            LinkHistory(
                f.link,
                "unmatched",
                f"{_flag_words(f)}; counted from the link at the sensor at the start{_ambiguous(f)}",
                (_visit(m_now, f),),
                tuple(f.alternatives),
            )
            for f in s_now.flagged
        )
        statement = (
            f"the link numbers of the {day} scan count from whichever link was at the sensor when the recording "
            "started (no marker): they name no physical link and cannot be matched with another visit's; record "
            "with a marked link (the catalogue's marker_s) to follow a link across visits"
        )
        return UnitLinks(str(unit), visits, False, statement, links, k)
    earlier = [(m, s) for m, s in done[:-1] if s.marker_s is not None and s.n_links == s_now.n_links]
    if not earlier:
        links = tuple(
            LinkHistory(
                f.link,
                "flagged",
                f"{_flag_words(f)}; no earlier scan counts from the marked link{_ambiguous(f)}",
                (_visit(m_now, f),),
                tuple(f.alternatives),
            )
            for f in s_now.flagged
        )
        others = len(done) - 1
        statement = (
            f"the {day} scan counts from the marked link; no earlier scan of unit {unit} does"
            + (f" ({others} earlier scan(s) count from the link at the sensor at their start)" if others else "")
            + ": nothing to compare yet"
        )
        return UnitLinks(str(unit), visits, False, statement, links, k)
    marked = earlier + [(m_now, s_now)]
    m_before, s_before = earlier[-1]
    out = []
    for g in _follow(marked):
        vs = tuple(_visit(m, f) for (m, _), f in zip(marked, g))
        now, before = vs[-1], vs[-2]
        latest = next(f for f in reversed(g) if f is not None)
        if now.flagged:
            verdict, words = _compare(now, before, k)
            words += _ambiguous(now)
        elif before.flagged:
            verdict, words = (
                "not flagged now",
                f"flagged on {before.date_utc[:10]}{_ambiguous(before) and ' as ' + before.label} "
                f"({_mm(before.excess_pitch_m)}), not now",
            )
        else:
            last = next(v for v in reversed(vs) if v.flagged)
            verdict, words = (
                "not flagged now",
                f"last flagged on {last.date_utc[:10]}{_ambiguous(last) and ' as ' + last.label}",
            )
        out.append(LinkHistory(latest.link, verdict, words, vs, tuple(latest.alternatives)))
    out.sort(key=lambda h: (_ORDER.get(h.verdict, 9), h.link))
    statement = (
        f"links numbered from the marked link on {len(marked)} visits; the {day} scan compared with "
        f"{m_before.date_utc[:10]}'s: worse is an excess grown by more than {k:g} combined sigmas (the same link "
        "must be marked at every visit)"
    )
    return UnitLinks(str(unit), visits, True, statement, tuple(out), k)
