"""odo_tools.resources: where the Python tools find the DBC, the robots and libodosim.so, in a
checkout and installed (the installed path end to end: tests/package/check_package.py)."""

import os
import stat
from pathlib import Path

from odo_tools import resources

SRC = Path(os.environ["ODO_SOURCE_DIR"])


def test_checkout_uses_the_repository_itself():
    assert resources.checkout_root() == SRC.resolve()
    assert resources.dbc_path() == SRC.resolve() / "can" / "odometry.dbc"
    assert resources.robot_path("labmate").is_file()


def test_package_data_are_the_repository_files():
    """odo_tools/data (what the wheel carries) resolves to the single copies, not to copies."""
    d = resources.DATA_DIR
    assert (d / "can/odometry.dbc").resolve() == (SRC / "can/odometry.dbc").resolve()
    for r in (SRC / "host_sim/robots").glob("*.json"):
        assert (d / "host_sim/robots" / r.name).read_bytes() == r.read_bytes()


def fake_prefix(root: Path) -> Path:
    (root / "bin").mkdir(parents=True)
    (root / "lib").mkdir()
    exe = root / "bin" / "odo-sim"
    exe.write_text("#!/bin/sh\n")
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    (root / "lib" / resources.LIB_NAME).write_bytes(b"")
    return root


def test_installed_lib_comes_from_the_prefix_of_odo_sim_on_path(tmp_path, monkeypatch):
    pre = fake_prefix(tmp_path / "usr")
    monkeypatch.delenv("ODO_BUILD_DIR", raising=False)
    monkeypatch.setenv("LD_LIBRARY_PATH", "")
    monkeypatch.setenv("PATH", f"{pre / 'bin'}:/usr/bin:/bin")
    assert resources.installed_lib() == pre.resolve() / "lib" / resources.LIB_NAME


def test_odo_build_dir_comes_first(tmp_path, monkeypatch):
    pre = fake_prefix(tmp_path / "usr")
    other = tmp_path / "build"
    (other / "lib").mkdir(parents=True)
    (other / "lib" / resources.LIB_NAME).write_bytes(b"")
    monkeypatch.setenv("PATH", f"{pre / 'bin'}:/usr/bin:/bin")
    monkeypatch.setenv("ODO_BUILD_DIR", str(other))
    assert resources.installed_lib() == other / "lib" / resources.LIB_NAME


def test_a_checkout_exports_nothing(monkeypatch):
    monkeypatch.delenv("ODO_SOURCE_DIR", raising=False)
    monkeypatch.delenv("ODO_BUILD_DIR", raising=False)
    resources.export_for_gap()
    assert "ODO_SOURCE_DIR" not in os.environ and "ODO_BUILD_DIR" not in os.environ


def test_installed_exports_the_wheel_data_and_the_prefix(tmp_path, monkeypatch):
    pre = fake_prefix(tmp_path / "usr")
    monkeypatch.setattr(resources, "checkout_root", lambda: None)
    monkeypatch.delenv("ODO_SOURCE_DIR", raising=False)
    monkeypatch.delenv("ODO_BUILD_DIR", raising=False)
    monkeypatch.setenv("LD_LIBRARY_PATH", "")
    monkeypatch.setenv("PATH", f"{pre / 'bin'}:/usr/bin:/bin")
    resources.export_for_gap()
    assert os.environ["ODO_SOURCE_DIR"] == str(resources.DATA_DIR)
    assert os.environ["ODO_BUILD_DIR"] == str(pre.resolve())
    # a value the user set is kept
    monkeypatch.setenv("ODO_BUILD_DIR", "/mine")
    resources.export_for_gap()
    assert os.environ["ODO_BUILD_DIR"] == "/mine"
