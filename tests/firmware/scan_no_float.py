#!/usr/bin/env python3
"""ctest firmware.no_float_source_scan: no floating point or heap words in firmware/ sources.

Scans firmware/**/*.c and *.h for the words float, double, malloc, calloc and realloc outside
comments and string/character literals, and fails listing file:line for each. The only exception is
the `#pragma GCC poison` line of firmware/src/odo_fw.h, which has to name them. This complements the
poison prelude: it also covers headers and code under `#if` branches the compiler never sees.

Usage: scan_no_float.py FIRMWARE_DIR     (exit 0: clean, 1: words found, 2: usage or I/O error)
       scan_no_float.py --self-test      (checks the comment/literal stripping on fixtures)
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

FORBIDDEN = re.compile(r"\b(float|double|malloc|calloc|realloc)\b")
POISON_LINE = re.compile(r"^\s*#\s*pragma\s+GCC\s+poison\b")
POISON_FILE = Path("src") / "odo_fw.h"


def strip_comments_and_literals(text: str) -> str:
    """Blank out comments and string/char literals, keeping every newline so line numbers hold."""
    out: list[str] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        nxt = text[i + 1] if i + 1 < n else ""
        if c == "/" and nxt == "/":
            j = text.find("\n", i)
            j = n if j < 0 else j
            # A backslash-newline continues a // comment onto the next line.
            while j < n and j > 0 and text[j - 1] == "\\":
                k = text.find("\n", j + 1)
                j = n if k < 0 else k
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "/" and nxt == "*":
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + re.sub(r"[^\n]", " ", text[i + 1 : j - 1]) + c)
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def scan_text(text: str, allow_poison_pragma: bool) -> list[tuple[int, str, str]]:
    """Return (line number, word, original line) for every forbidden word in code."""
    hits = []
    original = text.splitlines()
    for lineno, line in enumerate(
        strip_comments_and_literals(text).splitlines(), start=1
    ):
        if allow_poison_pragma and POISON_LINE.match(line):
            continue
        for m in FORBIDDEN.finditer(line):
            hits.append((lineno, m.group(1), original[lineno - 1].strip()))
    return hits


def scan_tree(firmware_dir: Path) -> list[str]:
    problems = []
    files = sorted(
        p for p in firmware_dir.rglob("*") if p.suffix in (".c", ".h") and p.is_file()
    )
    if not files:
        raise FileNotFoundError(f"no .c/.h files under {firmware_dir}")
    for path in files:
        rel = path.relative_to(firmware_dir)
        text = path.read_text(encoding="utf-8", errors="replace")
        for lineno, word, line in scan_text(
            text, allow_poison_pragma=(rel == POISON_FILE)
        ):
            problems.append(f"firmware/{rel.as_posix()}:{lineno}: `{word}`: {line}")
    return problems


def self_test() -> int:
    fixture = (
        "/* double in a block comment */\n"
        "// float in a line comment\n"
        'static const char *s = "malloc in a string";\n'
        "char q = '\\'';  /* escaped quote, then code: */ int doubled;\n"
        "#pragma GCC poison float double\n"
        "int32_t x; double y;\n"
        "void *p = calloc(1, 2); /* and a comment */\n"
        "float_t ok_identifier; realloc_count = 0;\n"
    )
    hits = [(ln, w) for ln, w, _ in scan_text(fixture, allow_poison_pragma=False)]
    want = [(5, "float"), (5, "double"), (6, "double"), (7, "calloc")]
    hits_allowed = [
        (ln, w) for ln, w, _ in scan_text(fixture, allow_poison_pragma=True)
    ]
    want_allowed = [(6, "double"), (7, "calloc")]
    if hits != want or hits_allowed != want_allowed:
        print(
            f"self-test FAILED: got {hits} / {hits_allowed}, want {want} / {want_allowed}"
        )
        return 1
    print("self-test ok")
    return 0


def main(argv: list[str]) -> int:
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    firmware_dir = Path(argv[1])
    if self_test() != 0:
        return 1
    try:
        problems = scan_tree(firmware_dir)
    except OSError as e:
        print(
            f"firmware.no_float_source_scan: cannot scan {firmware_dir}: {e}",
            file=sys.stderr,
        )
        return 2
    if problems:
        print(
            "firmware.no_float_source_scan FAILED: floating-point or heap words in firmware/ "
            "code (outside comments and literals):"
        )
        for p in problems:
            print("  " + p)
        return 1
    print(
        f"firmware.no_float_source_scan: {firmware_dir} is free of float/double/malloc/calloc/"
        "realloc outside comments"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
