"""Long work shows progress on a terminal; piped, it is quiet for short work and prints a line every few
seconds for long work (a service or cron job must not run silently for minutes)."""

import io

import vibkit
from vibkit.runtime.progress import Progress


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


def test_simulation_is_quiet_on_a_pipe(capfd, monkeypatch):
    """pytest's captured stderr is not a terminal: a short forward run prints nothing there (the
    interval is raised so that a first compilation of the kernels cannot count as long work)."""
    from pathlib import Path

    monkeypatch.setenv("VIBKIT_PROGRESS_INTERVAL", "1e9")
    vibkit.simulate(Path(__file__).resolve().parents[2] / "sim" / "thesis-forward.toml", duration=0.2)
    assert capfd.readouterr().err == ""


def test_lines_when_piped_and_long(monkeypatch):
    """Not a terminal: one line per interval with the fraction done, then a closing line; no bar."""
    import time

    monkeypatch.setenv("VIBKIT_PROGRESS_INTERVAL", "0.05")
    piped = io.StringIO()
    bar = Progress(4, "work", stream=piped)
    for i in range(1, 5):
        time.sleep(0.06)
        bar.update(i)
    bar.close()
    lines = piped.getvalue().splitlines()
    assert lines[0] == "work: 25.0 % after 0 s"
    assert lines[-2].startswith("work: 100.0 % after") and lines[-1].startswith("work: done after")
    assert len(lines) == 5 and "\r" not in piped.getvalue() and "#" not in piped.getvalue()


def test_no_line_before_the_interval(monkeypatch):
    monkeypatch.setenv("VIBKIT_PROGRESS_INTERVAL", "1e9")
    piped = io.StringIO()
    bar = Progress(4, "work", stream=piped)
    bar.update(2)
    bar.close()
    assert piped.getvalue() == ""


def test_kinematic_sweep_shows_lines_when_piped(monkeypatch, capfd):
    """Long kinematic sweeps are not silent off a terminal; pieces of a chunked compiled sweep give
    the same delta as one piece (warm-started from the last), to the closure tolerance."""
    from pathlib import Path

    import numpy as np

    import vibkit.analyses.kinematics as kin
    from vibkit.model.escalator import EscalatorModel
    from vibkit.model.scene import load_scene

    monkeypatch.setenv("VIBKIT_PROGRESS_INTERVAL", "1e-9")
    model = EscalatorModel(load_scene(Path(__file__).resolve().parents[2] / "sim" / "thesis-kinematics.toml"))
    whole = kin.kinematic_sweep(model, 3.0, 3.05, 0.001)
    monkeypatch.setattr(kin, "PROGRESS_CHUNK", 7)
    pieces = kin.kinematic_sweep(model, 3.0, 3.05, 0.001, progress=True)
    np.testing.assert_allclose(pieces.delta.values, whole.delta.values, rtol=0, atol=1e-12)
    err = capfd.readouterr().err
    assert "kinematic sweep: " in err and "kinematic sweep: done" in err
    kin.kinematic_sweep(model, 3.0, 3.05, 0.001, rollers=(1,), outputs=("delta", "roller_position"), progress=True)
    err = capfd.readouterr().err
    assert "kinematic sweep: 0.0 %" in err and "kinematic sweep: done" in err


def test_a_note_on_compiling_is_said_at_once_on_a_terminal_and_with_the_first_line_in_a_log(monkeypatch):
    """A first run after an install compiles the kernels for about a minute before the bar moves: the bar says
    so at once; a log's first line carries it (not every line)."""
    import time

    monkeypatch.setenv("TERM", "xterm")
    tty = FakeTTY()
    Progress(10, "work", stream=tty, note="compiling").close()
    assert tty.getvalue().startswith("work: compiling\n")
    monkeypatch.setenv("VIBKIT_PROGRESS_INTERVAL", "0.05")
    piped = io.StringIO()
    bar = Progress(2, "work", stream=piped, note="compiling")
    assert piped.getvalue() == ""  # a short run stays quiet
    for i in (1, 2):
        time.sleep(0.06)
        bar.update(i)
    lines = piped.getvalue().splitlines()
    assert lines[0] == "work: 50.0 % after 0 s (compiling)" and "compiling" not in lines[1]


def test_a_kernel_is_cached_when_its_index_is_in_the_modules_pycache(tmp_path, monkeypatch):
    """An index numba wrote for the source as it is (its stamp: the source's modification time and size) beside
    it; an empty or unreadable index file is none (numba would compile again)."""
    import os
    import pickle

    from vibkit.runtime import kernel_cache
    from vibkit.runtime.kernel_cache import kernel_cached

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setitem(kernel_cache._STATE, "dir", None)
    module = tmp_path / "pitch_table.py"
    module.write_text("")
    (tmp_path / "__pycache__").mkdir()
    assert not kernel_cached(str(module), "rhs")
    index = tmp_path / "__pycache__" / "pitch_table.rhs-667.py311.nbi"
    index.write_bytes(b"")
    assert not kernel_cached(str(module), "rhs")
    st = os.stat(module)
    index.write_bytes(pickle.dumps("0.59.1") + pickle.dumps(((st.st_mtime, st.st_size), {})))
    assert kernel_cached(str(module), "rhs") and not kernel_cached(str(module), "table_delta")


def test_a_kernel_numba_itself_cached_is_known_cached_and_an_edit_makes_it_cold(tmp_path, monkeypatch):
    """Against numba's own index, whatever its stamp (a digest of the source from numba 0.68 on, its modification
    time and size before): a kernel compiled with ``cache=True`` is cached; the source edited, it is not (numba would
    compile again), so a command says "compiling" exactly when it will."""
    import os
    import subprocess
    import sys
    import textwrap

    from vibkit.runtime import kernel_cache
    from vibkit.runtime.kernel_cache import kernel_cached

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setitem(kernel_cache._STATE, "dir", None)
    module = tmp_path / "tiny_kernel.py"
    module.write_text("import numba\n\n\n@numba.njit(cache=True)\ndef kern(x):\n    return x + 1.0\n")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    run = textwrap.dedent(
        f"""
        import sys
        sys.path.insert(0, {str(tmp_path)!r})
        import tiny_kernel
        assert tiny_kernel.kern(1.0) == 2.0
        """
    )
    assert not kernel_cached(str(module), "kern")
    subprocess.run([sys.executable, "-c", run], check=True, env=env, cwd=tmp_path)
    assert kernel_cached(str(module), "kern") and not kernel_cached(str(module), "other")
    module.write_text(module.read_text() + "\n# edited\n")
    assert not kernel_cached(str(module), "kern")
