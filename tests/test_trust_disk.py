"""A sweep on a disk that fills up leaves no empty or cut picture (issue 20, case 7).

A real full disk: a small tmpfs mounted for the test (it needs the right to mount, as root in a
container or a VM has; elsewhere the test is skipped), filled to leave a few KiB, then
``shoal sweep`` writes into it. At some free space the tables fit and a picture does not; a
picture whose bytes stayed in the write buffer used to fail only when the file was closed,
after Pillow's clean-up, and was left empty. Now every file left is whole (a PNG is written
completely or not at all), and the command says in one line that it cannot write the folder.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

CLI = [sys.executable, "-m", "shoal"]
SIZE_KIB = 128


@pytest.fixture
def small_disk(tmp_path):
    where = tmp_path / "disk"
    where.mkdir()
    mount = shutil.which("mount")
    if mount is None or os.geteuid() != 0:
        pytest.skip("needs root and mount(8) to make a small file system")
    made = subprocess.run([mount, "-t", "tmpfs", "-o", f"size={SIZE_KIB}k", "tmpfs", str(where)], capture_output=True)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {made.stderr.decode()[-200:]}")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=True)


@pytest.mark.parametrize("free_kib", [4, 12, 20, 24, 28, 36])
def test_a_sweep_on_a_full_disk_leaves_no_empty_or_cut_png(small_disk, free_kib):
    (small_disk / "filler").write_bytes(b"\0" * ((SIZE_KIB - free_kib) * 1024))
    out = small_disk / "sweep"
    p = subprocess.run([*CLI, "sweep", "default", "--grid", "controller.U=4,6,9", "--runs", "2", "--steps", "10",
                        "--out", str(out)], capture_output=True, text=True, timeout=300)
    if p.returncode == 0:
        pytest.skip(f"{free_kib} KiB were enough for the whole sweep")
    assert p.returncode == 1 and "cannot write" in p.stderr and "Traceback" not in p.stderr, p.stderr[-2000:]
    # every file but the sweep's lock (empty by design) must be whole
    files = [f for f in out.rglob("*") if f.is_file() and f.name != ".lock"] if out.exists() else []
    assert all(f.stat().st_size > 0 for f in files), [f.name for f in files if f.stat().st_size == 0]
    for png in (f for f in files if f.suffix == ".png"):
        assert png.read_bytes().endswith(b"IEND\xaeB`\x82"), f"{png.name} is cut"
    assert not [f.name for f in files if ".partial-" in f.name]
