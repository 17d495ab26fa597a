"""The user's cache folder: only the user's own folders and regular files are used, and a kept payload only under
its own key with its own hash."""

import os

import pytest

from vibkit.runtime import user_cache as uc


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "vibkit"


def test_the_folder_is_under_xdg_cache_home_and_private(cache):
    folder = uc.private_folder("scenes")
    assert folder == cache / "scenes"
    assert os.stat(folder).st_mode & 0o777 == 0o700


def test_a_relative_xdg_cache_home_is_not_used(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")
    monkeypatch.setenv("HOME", str(tmp_path))
    assert uc.cache_root() == tmp_path / ".cache" / "vibkit"


def test_a_folder_that_is_a_link_or_open_to_others_is_refused(cache, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(mode=0o700)
    cache.mkdir(parents=True)
    (cache / "scenes").symlink_to(elsewhere)
    assert uc.private_folder("scenes") is None
    (cache / "signatures").mkdir()
    os.chmod(cache / "signatures", 0o755)  # readable by others: a private folder is not
    assert uc.private_folder("signatures") is None
    os.chmod(cache, 0o777)  # the cache folder itself writable by others
    assert uc.private_folder("other") is None


def test_only_the_user_s_own_regular_file_is_read(cache, tmp_path):
    folder = uc.private_folder("scenes")
    assert uc.write_atomic(folder, "a.toml", b"text")
    assert uc.read_checked(folder, "a.toml") == b"text"
    target = tmp_path / "target"
    target.write_bytes(b"planted")
    (folder / "link.toml").symlink_to(target)
    assert uc.read_checked(folder, "link.toml") is None
    os.mkfifo(folder / "fifo.toml")
    assert uc.read_checked(folder, "fifo.toml") is None  # and does not block
    (folder / "open.toml").write_bytes(b"planted")
    os.chmod(folder / "open.toml", 0o666)
    assert uc.read_checked(folder, "open.toml") is None
    assert uc.read_checked(folder, "a.toml", max_bytes=3) is None
    assert uc.read_checked(folder, "missing.toml") is None
    # a store over the link replaces the link, never writes through it
    assert uc.write_atomic(folder, "link.toml", b"ours")
    assert target.read_bytes() == b"planted" and uc.read_checked(folder, "link.toml") == b"ours"


def test_a_payload_is_given_back_only_under_its_key_and_unchanged(cache):
    folder = uc.private_folder("signatures")
    assert uc.store_blob(folder, "key A", b"\x00payload\n1")
    assert uc.load_blob(folder, "key A") == b"\x00payload\n1"
    assert uc.load_blob(folder, "key B") is None
    name = next(p for p in folder.iterdir() if not p.name.startswith("."))
    data = name.read_bytes()
    for bad in (b"", data[:-1], data[:-1] + b"2", data.replace(b"vibkit-cache 1", b"vibkit-cache 2")):
        name.write_bytes(bad)
        assert uc.load_blob(folder, "key A") is None, bad
    # another key's whole file under this key's name
    uc.store_blob(folder, "key B", b"other")
    other = next(p for p in folder.iterdir() if p != name and not p.name.startswith("."))
    name.write_bytes(other.read_bytes())
    assert uc.load_blob(folder, "key A") is None


def test_without_a_usable_cache_folder_a_private_temporary_one_is_used(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "file"))
    (tmp_path / "file").write_text("not a folder")
    assert uc.private_folder("scenes") is None
    folder = uc.private_temp_folder("scenes-test")
    assert folder == uc.private_temp_folder("scenes-test")
    assert os.stat(folder).st_mode & 0o777 == 0o700
    assert folder.name.startswith("vibkit-scenes-test-") and len(folder.name) > len("vibkit-scenes-test-")
