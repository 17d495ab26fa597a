"""Long work shows progress on a terminal and is quiet when piped."""

import io

import vibkit
from vibkit.progress import Progress


class FakeTTY(io.StringIO):
    def isatty(self):
        return True


def test_draws_on_a_terminal(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    out = FakeTTY()
    bar = Progress(10, "work", stream=out)
    for i in range(11):
        bar.update(i)
    bar.close()
    text = out.getvalue()
    assert "work [" in text and "100.0%" in text and text.endswith("\n")


def test_quiet_when_piped_or_disabled(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    piped = io.StringIO()  # isatty() is False
    bar = Progress(10, "work", stream=piped)
    bar.update(5)
    bar.close()
    assert piped.getvalue() == ""
    tty = FakeTTY()
    bar = Progress(10, "work", stream=tty, enabled=False)
    bar.update(5)
    bar.close()
    assert tty.getvalue() == ""


def test_simulation_is_quiet_on_a_pipe(capfd):
    """pytest's captured stderr is not a terminal: a forward run prints nothing there."""
    from pathlib import Path

    vibkit.simulate(Path(__file__).resolve().parents[1] / "sim" / "thesis-forward.toml", duration=0.2)
    assert capfd.readouterr().err == ""
