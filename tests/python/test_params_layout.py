"""Parameter block layout (DESIGN s. 4, firmware/include/odo/odo_params.h).

The C encoder, run through `odo-params defaults`, puts every documented default at its documented
offset, little-endian, with the zlib CRC-32 at the end; `odo-params show` refuses damaged blocks and
names why.

The offsets and defaults below are copied by hand from the header's layout table, deliberately not
derived from the C code, so a slip on either side shows up here.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import zlib
from pathlib import Path

import pytest

BLOCK_SIZE = 128
CRC_OFFSET = 124

# (offset, struct format, documented default, name) from the header's byte layout table.
HEADER_FIELDS = [
    (0, "4s", b"ODOP", "magic"),
    (4, "H", 1, "version"),
    (6, "H", 128, "length"),
    (8, "B", 0, "vehicle (SINGLE)"),
    (9, "B", 24, "counter_bits"),
    (10, "B", 0, "heading_form (MIDPOINT)"),
    (11, "B", 0, "ipec_mode (OFF)"),
    (12, "I", 40_000, "tick_us"),
    (16, "I", 3_000, "max_wheel_speed_mm_s"),
]
TRUCK_STARTS = (20, 48)
Q30_ONE = 1 << 30
TRUCK_FIELDS = [  # offsets relative to the truck record
    (0, "I", 150_000_000, "wheel_diameter_nm"),
    (4, "I", 39_000_000, "counts_per_rev_milli"),  # 500 lines * 4 * 19.5 gear, x1000
    (8, "I", 340_000_000, "wheelbase_nm"),
    (12, "i", Q30_ONE, "ed_q30"),
    (16, "i", Q30_ONE, "eb_q30"),
    (20, "i", Q30_ONE, "es_q30"),
    (24, "B", 0, "flags"),
]
LINK_FIELDS = [
    (76, "I", 1_000_000_000, "link.length_nm"),
    (80, "I", 0, "link.hitch_offset_nm"),
    (84, "i", 0, "link.length_bias_nm"),
    (88, "i", 0, "link.length_ecc_nm"),
    (92, "i", 0, "link.alpha_bias_bam"),
    (96, "i", 0, "link.beta_bias_bam"),
    (100, "B", 10, "link.rotary_bits"),
    (102, "H", 3, "link.stale_ticks"),
    (104, "I", round(10 / 360 * 2**32), "link.max_jump_bam"),
    (108, "I", 20_000, "link.max_length_jump_um"),
    (112, "I", 900_000, "link.length_min_um"),
    (116, "I", 1_100_000, "link.length_max_um"),
]
RESERVED = [
    20 + 25,
    20 + 26,
    20 + 27,
    48 + 25,
    48 + 26,
    48 + 27,
    101,
    120,
    121,
    122,
    123,
]


def _tool() -> str:
    build = os.environ.get("ODO_BUILD_DIR")
    if not build:
        pytest.skip("ODO_BUILD_DIR not set (run through ctest)")
    path = Path(build) / "bin" / "odo-params"
    if not path.is_file():
        pytest.fail(f"{path} not built")
    return str(path)


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [_tool(), *args], check=False, capture_output=True, text=True, timeout=30
    )


@pytest.fixture()
def default_block(tmp_path: Path) -> bytes:
    out = tmp_path / "params.bin"
    r = _run("defaults", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.bin"], (
        "temporary file left behind"
    )
    return out.read_bytes()


def test_default_block_is_128_bytes_with_odop_header(default_block: bytes) -> None:
    assert len(default_block) == BLOCK_SIZE
    assert default_block[:4] == b"ODOP"
    magic, version, length = struct.unpack_from("<IHH", default_block, 0)
    assert magic == 0x504F444F
    assert (version, length) == (1, 128)


def test_every_documented_offset_holds_its_default(default_block: bytes) -> None:
    fields = [*HEADER_FIELDS, *LINK_FIELDS]
    for start in TRUCK_STARTS:
        fields += [
            (start + off, fmt, val, f"truck@{start}.{name}")
            for off, fmt, val, name in TRUCK_FIELDS
        ]
    for off, fmt, want, name in fields:
        (got,) = struct.unpack_from("<" + fmt, default_block, off)
        assert got == want, f"{name} at offset {off}: {got!r} != {want!r}"


def test_layout_table_covers_every_byte_once() -> None:
    sizes = {"B": 1, "H": 2, "I": 4, "i": 4, "4s": 4}
    owned = [0] * BLOCK_SIZE
    spans = [(off, sizes[fmt]) for off, fmt, _, _ in [*HEADER_FIELDS, *LINK_FIELDS]]
    spans += [
        (s + off, sizes[fmt]) for s in TRUCK_STARTS for off, fmt, _, _ in TRUCK_FIELDS
    ]
    spans += [(off, 1) for off in RESERVED] + [(CRC_OFFSET, 4)]
    for off, n in spans:
        for i in range(off, off + n):
            owned[i] += 1
    assert owned == [1] * BLOCK_SIZE


def test_reserved_bytes_are_zero(default_block: bytes) -> None:
    assert [default_block[i] for i in RESERVED] == [0] * len(RESERVED)


def test_trailing_crc_is_zlib_crc32_of_the_first_124_bytes(
    default_block: bytes,
) -> None:
    (stored,) = struct.unpack_from("<I", default_block, CRC_OFFSET)
    assert stored == zlib.crc32(default_block[:CRC_OFFSET])


def test_show_prints_the_defaults_as_json(default_block: bytes, tmp_path: Path) -> None:
    f = tmp_path / "p.bin"
    f.write_bytes(default_block)
    r = _run("show", str(f))
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["status"] == "ok"
    assert doc["counter_bits"] == 24 and doc["tick_us"] == 40_000
    assert [t["wheelbase_nm"] for t in doc["truck"]] == [340_000_000] * 2
    assert doc["link"]["max_jump_bam"] == round(10 / 360 * 2**32)


@pytest.mark.parametrize("offset", [8, 40, 100, 123, 124, 127])
def test_show_rejects_a_corrupted_byte_naming_the_crc(
    default_block: bytes, tmp_path: Path, offset: int
) -> None:
    bad = bytearray(default_block)
    bad[offset] ^= 0x5A
    f = tmp_path / "bad.bin"
    f.write_bytes(bad)
    r = _run("show", str(f))
    assert r.returncode != 0
    assert "CRC" in r.stderr
    assert json.loads(r.stdout)["status"] == "crc"


def test_show_rejects_a_truncated_file(default_block: bytes, tmp_path: Path) -> None:
    for n in (0, 7, 64, 127):
        f = tmp_path / f"short{n}.bin"
        f.write_bytes(default_block[:n])
        r = _run("show", str(f))
        assert r.returncode != 0, n
        assert "short" in r.stderr, r.stderr


def test_show_names_the_field_of_a_range_error(
    default_block: bytes, tmp_path: Path
) -> None:
    bad = bytearray(default_block)
    struct.pack_into("<I", bad, 48 + 8, 0)  # truck B wheelbase_nm = 0, below 50 mm
    struct.pack_into("<I", bad, CRC_OFFSET, zlib.crc32(bytes(bad[:CRC_OFFSET])))
    f = tmp_path / "range.bin"
    f.write_bytes(bad)
    r = _run("show", str(f))
    assert r.returncode != 0
    assert "truck[1].wheelbase_nm" in r.stderr
    assert json.loads(r.stdout)["field"] == "truck[1].wheelbase_nm"


def test_defaults_into_a_nonexistent_directory_fails_and_leaves_nothing(
    tmp_path: Path,
) -> None:
    target = tmp_path / "missing" / "params.bin"
    r = _run("defaults", "--out", str(target))
    assert r.returncode != 0
    assert r.stderr.strip()
    assert list(tmp_path.iterdir()) == []


def test_defaults_under_a_plain_file_fails_and_leaves_nothing(tmp_path: Path) -> None:
    # A path component that is a file fails with ENOTDIR, even for root (unlike a read-only dir).
    blocker = tmp_path / "blocker"
    blocker.write_bytes(b"x")
    r = _run("defaults", "--out", str(blocker / "params.bin"))
    assert r.returncode != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


def test_defaults_into_a_read_only_directory_fails_and_leaves_nothing(
    tmp_path: Path,
) -> None:
    if os.geteuid() == 0:
        pytest.skip("root ignores directory permissions")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        r = _run("defaults", "--out", str(ro / "params.bin"))
        assert r.returncode != 0
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)


def test_defaults_onto_a_directory_fails_and_removes_its_temporary(
    tmp_path: Path,
) -> None:
    # The write succeeds but the rename cannot replace a directory: the .tmp must be cleaned up.
    (tmp_path / "params.bin").mkdir()
    r = _run("defaults", "--out", str(tmp_path / "params.bin"))
    assert r.returncode != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.bin"]


def test_help_exits_zero_for_the_tool_and_each_command() -> None:
    for args in (["--help"], ["defaults", "--help"], ["show", "--help"]):
        r = _run(*args)
        assert r.returncode == 0, args
        assert "usage:" in r.stdout
