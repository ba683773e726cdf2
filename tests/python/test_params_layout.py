"""Parameter block layout (DESIGN s. 4, firmware/include/odo/odo_params.h).

The layout has one source, the header's field table ODO_PARAMS_FIELDS. `odo-params layout`
expands it into params_layout.json in the build tree, and this test reads that file rather than
typing field names and offsets itself. What it checks against the table:

* the byte table a person reads in the header's comment (parsed here) says the same thing;
* the fields, header, reserved room and CRC cover every byte of each version exactly once;
* the C encoder, run through `odo-params defaults`, puts at each field's offset the value
  `odo-params show` prints under that field's name, with the zlib CRC-32 at the end;
* a version-1 block built here from those rules (zlib, struct) still shows, without the fields
  version 2 added; damaged blocks are refused naming what is wrong.
"""

from __future__ import annotations

import json
import os
import re
import struct
import subprocess
import zlib
from pathlib import Path
from typing import Any

import pytest

FMT = {"u8": "B", "u16": "H", "u32": "I", "i32": "i"}


def _build() -> Path:
    build = os.environ.get("ODO_BUILD_DIR")
    if not build:
        pytest.skip("ODO_BUILD_DIR not set (run through ctest)")
    return Path(build)


def _tool() -> str:
    path = _build() / "bin" / "odo-params"
    if not path.is_file():
        pytest.fail(f"{path} not built")
    return str(path)


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [_tool(), *args], check=False, capture_output=True, text=True, timeout=30
    )


@pytest.fixture(scope="module")
def layout() -> dict[str, Any]:
    path = Path(os.environ.get("ODO_PARAMS_LAYOUT") or _build() / "params_layout.json")
    assert path.is_file(), f"{path}: the build writes it (odo-params layout)"
    return json.loads(path.read_text())


def _header_text() -> str:
    src = os.environ.get("ODO_SOURCE_DIR", Path(__file__).resolve().parents[2])
    return (Path(src) / "firmware" / "include" / "odo" / "odo_params.h").read_text()


def _version(layout: dict[str, Any], v: int) -> dict[str, Any]:
    (entry,) = [e for e in layout["versions"] if e["version"] == v]
    return entry


def _spans(layout: dict[str, Any], version: int) -> list[tuple[int, int, str]]:
    """(offset, width, name) of the header, every field instance of `version`, and the CRC."""
    spans = [(h["offset"], h["width"], h["name"]) for h in layout["header"]]
    for f in layout["fields"]:
        if f["since"] > version:
            continue
        for t, off in enumerate(f["offsets"]):
            name = f"truck[{t}].{f['name']}" if f["scope"] == "truck" else f["name"]
            spans.append((off, f["width"], name))
    spans.append((_version(layout, version)["crc_offset"], 4, "crc32"))
    return spans


def _reserved(layout: dict[str, Any], version: int) -> list[int]:
    size = _version(layout, version)["size"]
    owned = [0] * size
    for off, width, _ in _spans(layout, version):
        for i in range(off, off + width):
            owned[i] += 1
    return [i for i in range(size) if owned[i] == 0]


def _json_value(doc: dict[str, Any], field: dict[str, Any], truck: int) -> int:
    if field["scope"] == "truck":
        return doc["truck"][truck][field["name"]]
    if field["scope"] == "link":
        return doc["link"][field["name"].removeprefix("link.")]
    return doc[field["name"]]


def _v1_of(layout: dict[str, Any], block: bytes) -> bytes:
    """A version-1 block from a version-2 one, by the header's rule: the same bytes up to the
    version-1 CRC, version 1, its length, its CRC."""
    v1 = _version(layout, 1)
    b = bytearray(block[: v1["crc_offset"]])
    struct.pack_into("<HH", b, 4, 1, v1["size"])
    return bytes(b) + struct.pack("<I", zlib.crc32(bytes(b)))


@pytest.fixture()
def default_block(tmp_path: Path) -> bytes:
    out = tmp_path / "params.bin"
    r = _run("defaults", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.bin"], (
        "temporary file left behind"
    )
    return out.read_bytes()


def _show(tmp_path: Path, data: bytes, name: str = "p.bin") -> tuple[int, dict, str]:
    f = tmp_path / name
    f.write_bytes(data)
    r = _run("show", str(f))
    return r.returncode, json.loads(r.stdout), r.stderr


# ---- the table itself -------------------------------------------------------------------------


def test_the_build_tree_layout_is_what_the_tool_prints_now(layout: dict[str, Any]) -> None:
    r = _run("layout")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == layout


def test_fields_header_reserved_and_crc_cover_each_version_once(
    layout: dict[str, Any],
) -> None:
    assert layout["version"] == max(e["version"] for e in layout["versions"])
    assert layout["size"] == _version(layout, layout["version"])["size"]
    for entry in layout["versions"]:
        v, size = entry["version"], entry["size"]
        assert entry["crc_offset"] == size - 4
        owned = [0] * size
        for off, width, name in _spans(layout, v):
            assert 0 <= off and off + width <= size, (v, name)
            for i in range(off, off + width):
                owned[i] += 1
        assert max(owned) == 1, f"version {v}: two things share a byte"
    # version 2 only appends: every version-1 field keeps its offset
    v1_fields = [f for f in layout["fields"] if f["since"] == 1]
    assert all(o < _version(layout, 1)["crc_offset"] for f in v1_fields for o in f["offsets"])
    assert [f["enum"] for f in layout["fields"]] == list(range(1, len(layout["fields"]) + 1))
    for f in layout["fields"]:
        assert struct.calcsize("<" + FMT[f["type"]]) == f["width"], f["name"]
        assert f["signed"] == (f["type"] == "i32"), f["name"]
        lo, hi = (-(2**31), 2**31 - 1) if f["signed"] else (0, 2 ** (8 * f["width"]) - 1)
        assert lo <= f["min"] <= f["max"] <= hi, f["name"]
        assert len(f["offsets"]) == (layout["trucks"] if f["scope"] == "truck" else 1)
        assert f["unit"], f["name"]


Row = tuple[int, int, "str | None", str]


def _doc_rows() -> tuple[list[Row], list[Row]]:
    """The byte table of the header comment: (absolute rows, truck-record rows), each
    (offset, size, type or None, name)."""
    text = _header_text()
    start = text.index("/// Byte layout, version 2")
    end = text.index("/// Version 1 (128 bytes")
    lines = [ln[3:] for ln in text[start:end].splitlines() if ln.startswith("///")]
    (head,) = [ln for ln in lines if re.match(r"\s+off\s+size\s+type\s+field\s+off", ln)]
    split = head.index("off", head.index("field"))
    row = re.compile(r"^\s*(\d+)\s+(\d+)\s+(?:(u8|u16|u32|i32)\s+)?(\S+)")
    absolute: list[Row] = []
    record: list[Row] = []
    in_record = False
    for ln in lines:
        left, right = ln[:split], ln[split:]
        if "truck record" in left:
            in_record = True
        for part, rows in ((left, record if in_record else absolute), (right, absolute)):
            m = row.match(part)
            if m:
                rows.append((int(m[1]), int(m[2]), m[3], m[4]))
    return absolute, record


def test_the_header_comment_table_matches_the_field_table(layout: dict[str, Any]) -> None:
    absolute, record = _doc_rows()
    doc = {name: (off, size, typ) for off, size, typ, name in absolute if name != "reserved"}
    rec = {name: (off, size, typ) for off, size, typ, name in record if name != "reserved"}
    starts = [doc[f"truck[{t}]"][0] for t in range(layout["trucks"])]
    record_size = doc["truck[0]"][1]
    for h in layout["header"]:
        assert doc[h["name"]][:2] == (h["offset"], h["width"]), h["name"]
    assert doc["CRC-32"][:2] == (layout["crc_offset"], 4)
    seen = set()
    for f in layout["fields"]:
        for t, off in enumerate(f["offsets"]):
            if f["scope"] != "truck":
                key, where = f["name"], doc
            elif f"truck[{t}].{f['name']}" in doc:
                key, where = f"truck[{t}].{f['name']}", doc
            else:  # inside the truck record table, relative to the record's start
                key, where = f["name"], rec
                off -= starts[t]
                assert 0 <= off < record_size, f["name"]
            assert key in where, f"{key}: not in the header's byte table"
            assert where[key] == (off, f["width"], f["type"]), key
            seen.add(key)
    extra = (set(doc) | set(rec)) - seen - {"magic", "version", "length", "CRC-32"}
    assert extra == {f"truck[{t}]" for t in range(layout["trucks"])}, extra
    # the reserved rows are exactly the bytes no field covers
    reserved = set()
    for off, size, _, name in absolute:
        if name == "reserved":
            reserved |= set(range(off, off + size))
    for off, size, _, name in record:
        if name == "reserved":
            reserved |= {s + i for s in starts for i in range(off, off + size)}
    assert sorted(reserved) == _reserved(layout, layout["version"])


# ---- the encoder, the decoder and the table agree ----------------------------------------------


def test_default_block_header_and_crc(layout: dict[str, Any], default_block: bytes) -> None:
    assert len(default_block) == layout["size"]
    magic, version, length = struct.unpack_from("<IHH", default_block, 0)
    assert default_block[:4] == layout["magic"].encode() and magic == layout["magic_u32"]
    assert (version, length) == (layout["version"], layout["size"])
    (stored,) = struct.unpack_from("<I", default_block, layout["crc_offset"])
    assert stored == zlib.crc32(default_block[: layout["crc_offset"]])


def test_every_field_offset_holds_what_show_prints_under_its_name(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path
) -> None:
    rc, doc, err = _show(tmp_path, default_block)
    assert rc == 0, err
    for f in layout["fields"]:
        for t, off in enumerate(f["offsets"]):
            (raw,) = struct.unpack_from("<" + FMT[f["type"]], default_block, off)
            assert raw == _json_value(doc, f, t), (f["name"], t, off)
            assert f["min"] <= raw <= f["max"], f["name"]  # the defaults validate
    # the JSON has exactly the table's keys
    top = {f["name"] for f in layout["fields"] if f["scope"] == "top"}
    meta = {"file", "status", "magic", "version", "length", "crc32", "truck", "link"}
    assert set(doc) == top | meta
    for t in range(layout["trucks"]):
        truck_names = {f["name"] for f in layout["fields"] if f["scope"] == "truck"}
        assert set(doc["truck"][t]) == truck_names
    assert set(doc["link"]) == {
        f["name"].removeprefix("link.") for f in layout["fields"] if f["scope"] == "link"
    }


def test_reserved_bytes_are_zero(layout: dict[str, Any], default_block: bytes) -> None:
    assert [default_block[i] for i in _reserved(layout, layout["version"])] == [0] * len(
        _reserved(layout, layout["version"])
    )


def test_show_prints_the_documented_defaults(default_block: bytes, tmp_path: Path) -> None:
    rc, doc, err = _show(tmp_path, default_block)
    assert rc == 0, err
    assert doc["status"] == "ok"
    assert doc["counter_bits"] == 24 and doc["tick_us"] == 40_000
    assert [t["wheelbase_nm"] for t in doc["truck"]] == [340_000_000] * 2
    assert [t["scrub_q30"] for t in doc["truck"]] == [0, 0]
    assert doc["link"]["max_jump_bam"] == round(10 / 360 * 2**32)


def test_a_version_1_block_shows_as_version_1_without_the_new_fields(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path
) -> None:
    rc, v2, err = _show(tmp_path, default_block, "v2.bin")
    assert rc == 0, err
    v1_block = _v1_of(layout, default_block)
    assert len(v1_block) == _version(layout, 1)["size"]
    rc, v1, err = _show(tmp_path, v1_block, "v1.bin")
    assert rc == 0, err
    assert (v1["version"], v1["length"]) == (1, len(v1_block))
    assert v1["crc32"] == f"0x{zlib.crc32(v1_block[:-4]):08X}"
    for f in layout["fields"]:
        for t in range(len(f["offsets"])):
            if f["since"] == 1:
                assert _json_value(v1, f, t) == _json_value(v2, f, t), f["name"]
            else:
                with pytest.raises(KeyError):
                    _json_value(v1, f, t)


# ---- refusals name what is wrong ---------------------------------------------------------------


@pytest.mark.parametrize("where", ["first", "field", "scrub", "tail", "crc"])
def test_show_rejects_a_corrupted_byte_naming_the_crc(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path, where: str
) -> None:
    scrub = next(f for f in layout["fields"] if f["since"] == 2)
    offset = {
        "first": layout["header_size"],
        "field": layout["fields"][-1]["offsets"][0],
        "scrub": scrub["offsets"][-1],
        "tail": _reserved(layout, 2)[-1],
        "crc": layout["size"] - 1,
    }[where]
    bad = bytearray(default_block)
    bad[offset] ^= 0x5A
    rc, doc, err = _show(tmp_path, bytes(bad))
    assert rc != 0
    assert "CRC" in err
    assert doc["status"] == "crc" and doc["field"] == "crc32"


def test_show_rejects_truncated_files_of_both_versions(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path
) -> None:
    for block in (default_block, _v1_of(layout, default_block)):
        for n in (0, 7, 64, len(block) - 1):
            rc, doc, err = _show(tmp_path, block[:n], f"short{n}.bin")
            assert rc != 0, n
            assert "short" in err and doc["status"] == "short", err


def _recrc(layout: dict[str, Any], b: bytearray) -> bytes:
    crc = layout["crc_offset"]
    struct.pack_into("<I", b, crc, zlib.crc32(bytes(b[:crc])))
    return bytes(b)


def test_show_names_the_field_of_a_range_error(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path
) -> None:
    # every truck field of truck B just outside its range, where the type allows it
    for f in layout["fields"]:
        if f["scope"] != "truck":
            continue
        lo = -(2**31) if f["signed"] else 0
        if f["min"] > lo:
            value = f["min"] - 1
        elif f["max"] < (2**31 - 1 if f["signed"] else 2 ** (8 * f["width"]) - 1):
            value = f["max"] + 1
        else:
            continue
        bad = bytearray(default_block)
        struct.pack_into("<" + FMT[f["type"]], bad, f["offsets"][1], value)
        rc, doc, err = _show(tmp_path, _recrc(layout, bad))
        assert rc != 0
        want = f"truck[1].{f['name']}"
        assert doc["field"] == want and want in err and str(value) in err, err


def test_show_names_version_length_and_reserved_refusals(
    layout: dict[str, Any], default_block: bytes, tmp_path: Path
) -> None:
    cases = []
    b = bytearray(default_block)
    struct.pack_into("<H", b, 4, layout["version"] + 1)
    cases.append((_recrc(layout, b), "version", "version", f"version {layout['version'] + 1}"))
    b = bytearray(default_block)
    struct.pack_into("<H", b, 6, _version(layout, 1)["size"])
    cases.append((_recrc(layout, b), "length", "length", f"length {_version(layout, 1)['size']}"))
    for at in (_reserved(layout, 2)[0], _reserved(layout, 2)[-1]):
        b = bytearray(default_block)
        b[at] = 1
        cases.append((_recrc(layout, b), "range", "reserved", f"offset {at} is 0x01"))
    for data, status, field, detail in cases:
        rc, doc, err = _show(tmp_path, data)
        assert rc != 0 and doc["status"] == status and doc["field"] == field, (status, err)
        assert detail in err, err


# ---- odo-params as a tool ----------------------------------------------------------------------


def test_defaults_into_a_nonexistent_directory_creates_it(tmp_path: Path) -> None:
    """The output rule (hostlib/odo_out.h): missing parent folders are created."""
    target = tmp_path / "missing" / "params.bin"
    r = _run("defaults", "--out", str(target))
    assert r.returncode == 0, r.stderr
    assert target.stat().st_size > 100
    assert [p.name for p in (tmp_path / "missing").iterdir()] == ["params.bin"]


def test_defaults_under_a_plain_file_fails_and_leaves_nothing(tmp_path: Path) -> None:
    # A path component that is a file fails with ENOTDIR, even for root (unlike a read-only dir).
    blocker = tmp_path / "blocker"
    blocker.write_bytes(b"x")
    r = _run("defaults", "--out", str(blocker / "params.bin"))
    assert r.returncode != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]
    r = _run("layout", "--out", str(blocker / "layout.json"))
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
    for args in (["--help"], ["defaults", "--help"], ["show", "--help"], ["layout", "--help"]):
        r = _run(*args)
        assert r.returncode == 0, args
        assert "usage:" in r.stdout
    r = _run("layout", "--frobnicate")
    assert r.returncode == 2 and "usage:" in r.stderr
