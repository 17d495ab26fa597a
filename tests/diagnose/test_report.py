"""The PDF report: its pages and their text, reproducible bytes, refusal to overwrite inputs."""

import re
from pathlib import Path

import pytest

from vibkit.diagnose.report import report_date, write_report

LEON = "data/field/leon-tensioner.csv"


def _page_count(path):
    return len(re.findall(rb"/Type\s*/Page\b", Path(path).read_bytes()))


@pytest.fixture(scope="module")
def leon_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("rep") / "leon.pdf"
    return write_report(LEON, out, scene="sim/leon.toml", duration=4.0)


@pytest.mark.slow
def test_pages_and_text(leon_report):
    rep = leon_report
    titles = [t for t, _ in rep.pages]
    assert titles == [
        "verdict",
        "recording",
        "time signal",
        "spectrum",
        "spectrogram",
        "order spectrum",
        "simulation against recording",
        "harmonics",
        "data quality",
        "parameters",
        "glossary",
    ]
    assert _page_count(rep.path) == len(titles)
    text = {t: "\n".join(x) for t, x in rep.pages}
    assert "leon-tensioner.csv" in text["recording"] and rep.summary["sha256"] in text["recording"]
    # no escalator profile: the unit is not named (a scene's description is not the unit's name)
    assert "unit not named: --escalator FILE" in text["verdict"] and "Leon shopping centre" not in text["verdict"]
    # verdict: the published link-pass and pitch, elongation against the catalogue pitch
    # the frequency the reconstruction was made with (3.54 Hz) within 2 of its sigma
    f, sf = (float(v) for v in re.search(r"(3\.5\d+) \+- (0\.000\d+) Hz", text["verdict"]).groups())
    assert abs(f - 3.54) <= 2 * sf
    # the file's speed states no uncertainty: the pitch to 0.01 mm and no +-
    assert re.search(r"138\.4\d mm \(speed uncertainty not stated\)", text["verdict"])
    assert "+- 0 " not in text["verdict"] and not re.search(r"\+- 0\.00\d\d mm", text["verdict"])
    assert "REPLACE" in text["verdict"] and "pitch differs from the recording" in text["verdict"]
    # lengths plotted in um, as the tables give them (the tensioner's ripple is tens of um)
    assert "frequency [Hz]" in text["spectrum"] and "amplitude [\u00b5m]" in text["spectrum"]
    assert "tensioner_displacement [\u00b5m]" in text["time signal"]
    assert "time [s]" in text["time signal"] and "6 spike(s) circled" in text["time signal"]  # the six spikes
    assert "order [cycles per link]" in text["order spectrum"]
    assert "simulation (delta)" in text["simulation against recording"]
    assert "6 metadata line(s) above the data kept as attrs" in text["data quality"]
    assert rep.summary["spikes"] == 6


@pytest.mark.slow
@pytest.mark.slow
def test_every_text_drawn_on_a_page_can_be_extracted_from_the_pdf(leon_report):
    """The PDF's text is searchable: every line of every text a page records (tables, notes, axis labels) is in
    what a PDF reader (pdfium) extracts from that page, whitespace aside and matplotlib's minus sign read as '-'."""
    pdfium = pytest.importorskip("pypdfium2")

    def norm(text):
        return re.sub(r"\s+", " ", text.replace("\u2212", "-")).strip()

    pdf = pdfium.PdfDocument(leon_report.path)
    checked = 0
    for (title, texts), page in zip(leon_report.pages, pdf, strict=True):
        extracted = norm(page.get_textpage().get_text_range())
        lines = [norm(line) for t in texts for line in t.splitlines() if norm(line) and "$" not in line]
        assert lines, title
        missing = [line for line in lines if line not in extracted]
        assert not missing, (title, missing[:3])
        checked += len(lines)
    pdf.close()
    assert checked > 200  # every page's texts, not a few


def test_reproducible_bytes(tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    a, b = tmp_path / "a.pdf", tmp_path / "b.pdf"
    ra = write_report(LEON, a)
    write_report(LEON, b)
    assert a.read_bytes() == b.read_bytes()
    assert "2023-11-14" in "\n".join(ra.pages[0][1])
    assert report_date().year == 2023


def test_report_date_is_today_without_source_date_epoch(monkeypatch):
    import datetime as dt

    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    before = dt.datetime.now(dt.timezone.utc).replace(microsecond=0)
    d = report_date()
    assert before <= d <= dt.datetime.now(dt.timezone.utc)


def test_refuses_to_overwrite_input(tmp_path):
    src = tmp_path / "rec.pdf"
    src.write_bytes(Path(LEON).read_bytes())
    with pytest.raises(ValueError, match="input"):
        write_report(src, src)
    assert src.read_bytes() == Path(LEON).read_bytes()


def test_bad_source_date_epoch(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    with pytest.raises(ValueError, match="SOURCE_DATE_EPOCH"):
        report_date()


def test_length_scale_reads_as_the_tables():
    from vibkit.diagnose.report.common import length_scale

    assert length_scale("m", 2.7e-5) == (1e6, "\u00b5m")
    assert length_scale("m", 0.033) == (1e3, "mm")
    assert length_scale("m", 2.5) == (1.0, "m")
    assert length_scale("m/s^2", 0.4) == (1.0, "m/s^2")
    assert length_scale("m", float("nan")) == (1.0, "m")


def test_without_a_speed_page_one_names_a_family_not_a_link_pass(tmp_path):
    # a walk (a phone in a pocket, phyphox): its 2.94 Hz family lies in the band, and without a speed nothing tells
    # it from a chain's link pass; page 1 says what was found and that it was not checked
    rep = write_report("data/thirdparty/phyphox_walking_linear_accelerometer.csv", tmp_path / "walk.pdf")
    text = "\n".join(rep.pages[0][1])
    assert "FAMILY AT 2.937 Hz" in text and "not checked as a link\npass" in text
    assert not any(line.startswith("LINK PASS") for line in rep.pages[0][1])  # the headline it gave before


@pytest.mark.slow
def test_a_worn_scene_s_nominal_pitch_is_its_sprocket_s(tmp_path, leon_report):
    """A stranger compared Leon with a scene of a 3 % elongated chain on the original sprocket: page 1 measured the
    elongation against the worn pitch and said OK (+0.79 % of 137.3 mm). The nominal pitch is the one the teeth are
    cut for: the same +3.8 % as with the healthy scene."""
    scene = tmp_path / "leon-elongated.toml"
    text = Path("sim/leon.toml").read_text()
    scene.write_text(text.replace("[chain]", "[chain]\nelongation_percent = 3.0", 1))
    rep = write_report(LEON, tmp_path / "r.pdf", scene=str(scene), duration=4.0)
    assert rep.summary["elongation_percent"] == pytest.approx(leon_report.summary["elongation_percent"], abs=1e-9)
    assert rep.summary["elongation_percent"] > 3.5 and rep.summary["verdict"] == "replace"


def test_a_pitch_at_the_scenes_own_speed_is_not_judged(tmp_path):
    """The Las Palmas recording states no speed: the report took the scene's nominal 0.52 m/s (itself read from
    the recording's 3.9 Hz) and judged the pitch "consistent", where `vibkit compare` says "not judged" (a
    stranger's find). Its pitch at that speed is the scene's by construction: not judged, said on page 1; with the
    speed given, judged."""
    lp, scene = "data/field/las-palmas-accelerometer.csv", "sim/las-palmas.toml"
    assumed = write_report(lp, tmp_path / "a.pdf", scene=scene, duration=6.0)
    assert assumed.summary["pitch_consistent"] is None
    # and the scene's set speed is a rated speed, known to EN 115-1's +-5 % (2.9 %): no elongation verdict at it
    # (page 1 said "OK, +0.00 %" at a speed read from the recording's own frequency)
    assert assumed.summary["speed_sigma_m_s"] == pytest.approx(0.05 / 3**0.5 * 0.52, rel=1e-9)
    assert (assumed.summary["status"], assumed.summary["verdict"]) == ("inconclusive", "inconclusive")
    given = write_report(lp, tmp_path / "g.pdf", scene=scene, duration=6.0, speed=0.52)
    assert given.summary["pitch_consistent"] is True


def test_an_inconclusive_record_gives_its_elongation_without_a_sigma(tmp_path, monkeypatch):
    """Page 1 of an inconclusive record printed its elongation with a sigma ("-0.52 +- 0.13 %" of a new chain on a
    stranger's step sensor) under "no verdict": the value is given to a tenth of a per cent and said to carry no
    sigma that holds."""
    from vibkit.diagnose.report.common import PageSink

    texts = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        found = (t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
        texts[title] = " ".join(x if isinstance(x, str) else x.get_text() for x in found)
        return orig(self, fig, title)

    monkeypatch.setattr(PageSink, "emit", emit)
    rep = write_report(
        "data/field/layouts/gcdc-x16.csv", tmp_path / "r.pdf", speed=0.52, speed_sigma=0.0005, nominal_pitch=0.13333
    )
    assert rep.summary["status"] == "inconclusive"
    page = " ".join(texts["verdict"].split())
    assert re.search(r"about [+-][0-9]+\.[0-9] % \(inconclusive: no verdict, no sigma that holds\)", page), page


def test_an_elongation_whose_sigma_is_known_but_too_large_keeps_it(tmp_path):
    """Inconclusive because the speed is a rated one (EN 115-1's 2.9 %): that sigma holds, only too large for a
    verdict, and the evidence gives it (the "no sigma that holds" wording is for estimates not to be trusted)."""
    from vibkit.diagnose.report.context import analyse
    from vibkit.diagnose.report.verdict import evidence_rows

    ctx = analyse("data/field/las-palmas-accelerometer.csv", scene="sim/las-palmas.toml", duration=4.0)
    rows = dict(evidence_rows(ctx))
    assert rows["elongation"] == "+0.0 +- 2.9 %"
