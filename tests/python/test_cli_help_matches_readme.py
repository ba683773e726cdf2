"""Every command line the README shows (its ```sh blocks and `inline` commands) uses only flags
that the tool's --help documents (issue 17: --help texts that match the README), and every C CLI
answers --help and --version. The README is read, not copied: a flag added to the README without
the help text, or dropped from a tool, fails here."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

BUILD = Path(os.environ["ODO_BUILD_DIR"])
SRC = Path(os.environ["ODO_SOURCE_DIR"])
PY_TOOLS = {"odo-gap", "odo-import", "odo-plot-umbmark", "odo-plot-demo", "odo-plot-realdata"}
SUBCOMMANDS = {
    "odo-calib": {"umbmark", "write", "read", "verify", "export", "fit", "acceptance"},
    "odo-ipec": {"goals", "trace", "selfcal", "selfcal-link"},
    "odo-params": {"defaults", "show", "layout"},
    "odo-gap": {"diagnose", "blind"},
    "odo-import": {"ticks-csv", "ros2-bag"},
}


def readme_commands() -> list[tuple[str, str, tuple[str, ...]]]:
    text = (SRC / "README.md").read_text()
    chunks = re.findall(r"```sh\n(.*?)```", text, flags=re.S)
    chunks += re.findall(r"`([^`\n]*odo-[a-z][^`\n]*)`", text)
    found = set()
    for chunk in chunks:
        for line in chunk.replace("\\\n", " ").splitlines():
            for m in re.finditer(r"(?:^|[\s/])(odo-[a-z][a-z0-9-]*)((?:\s+[^\s|;&#]+)*)", line):
                tool, rest = m.group(1), m.group(2).split()
                if not (BUILD / "bin" / tool).exists() and tool not in PY_TOOLS:
                    continue  # a word like odo-tools, or a target-only program
                sub = rest[0] if rest and rest[0] in SUBCOMMANDS.get(tool, ()) else ""
                flags = tuple(sorted({a.split("=")[0] for a in rest if re.match(r"--[a-z]", a)}))
                found.add((tool, sub, flags))
    return sorted(found)


COMMANDS = readme_commands()


def test_the_readme_shows_commands_of_every_kind() -> None:
    tools = {t for t, _, _ in COMMANDS}
    assert {"odo-sim", "odo-replay", "odo-calib", "odo-import", "odo-gap"} <= tools, tools


@pytest.mark.parametrize("tool,sub,flags", COMMANDS, ids=lambda v: str(v).replace(" ", ""))
def test_readme_flags_are_in_the_help(tool: str, sub: str, flags: tuple[str, ...]) -> None:
    exe = SRC / ".venv" / "bin" / tool if tool in PY_TOOLS else BUILD / "bin" / tool
    r = subprocess.run([str(exe), *([sub] if sub else []), "--help"], capture_output=True,
                       text=True, timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    helptext = r.stdout + r.stderr
    missing = [f for f in flags if f not in helptext]
    assert not missing, f"{tool} {sub} --help does not mention {missing}"
