"""Dependencies flow one way (issue 17): the repository's C include graph and Python import graph
have no cycles and no upward edges except firmware/app -> hal/hal.h, no target's objects depend on
each other both ways (tests/lint/layers.py), and the checker itself fails on graphs that break
those rules."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(os.environ.get("ODO_SOURCE_DIR") or Path(__file__).resolve().parents[2])
sys.path.insert(0, str(ROOT / "tests" / "lint"))

import layers  # noqa: E402


def test_repository_dependencies_flow_one_way() -> None:
    violations, stats = layers.check_tree(ROOT)
    assert violations == []
    # The graphs were really read: every layer's C and the whole odo_tools package.
    assert stats["c_files"] > 100 and stats["c_edges"] > 200
    assert stats["py_modules"] > 20 and stats["py_edges"] > 30


def test_the_repository_graph_holds_the_edges_the_layering_is_about() -> None:
    cg, problems = layers.c_graph(ROOT)
    assert problems == []
    assert "hal/hal.h" in cg["firmware/app/odo_loop.c"]  # the one allowed upward edge
    assert "hal/sim/hctl1100.h" in cg["hal/sim/hal_sim.h"]  # the emulator now sits in hal
    assert "hal/log/hal_log.h" in cg["hostlib/odo_candump.c"]  # one candump formatter
    assert "host_sim/include/odosim/odosim_sil.h" in cg["host_sim/cli/odo-sim.c"]


def test_checker_flags_a_folder_cycle_and_upward_edges() -> None:
    graph = {
        "hal/sim/hal_sim.h": {"host_sim/src/hctl1100.h", "hal/hal.h"},
        "host_sim/src/world.c": {"host_sim/run/sil.h"},
        "host_sim/run/sil.c": {"host_sim/src/world.h", "hal/sim/hal_sim.h"},
        "firmware/src/odo_fx.c": {"firmware/app/odo_app.h"},
        "hostlib/odo_robot.c": {"tools/lib/odo_ref.h"},
    }
    v = layers.check_c(graph)
    assert "upward: hal/sim/hal_sim.h -> host_sim/src/hctl1100.h" in v
    assert "upward: firmware/src/odo_fx.c -> firmware/app/odo_app.h" in v
    assert "upward: hostlib/odo_robot.c -> tools/lib/odo_ref.h" in v
    assert "cycle between folders: hal/sim <-> host_sim/run <-> host_sim/src" in v
    # reaching into host_sim's internals from below is also a private edge
    assert "private: hal/sim/hal_sim.h -> host_sim/src/hctl1100.h (use host_sim/include)" in v
    # downward and same-layer edges are fine
    assert not any("hal/sim/hal_sim.h -> hal/hal.h" in x for x in v)
    assert not any("host_sim/run/sil.c -> hal/sim" in x for x in v)
    assert len(v) == 5


def test_only_firmware_app_may_include_the_hal_door() -> None:
    assert layers.check_c({"firmware/app/odo_loop.c": {"hal/hal.h"}}) == []
    assert layers.check_c({"firmware/app/odo_loop.c": {"hal/sim/hal_sim.h"}}) == [
        "upward: firmware/app/odo_loop.c -> hal/sim/hal_sim.h"
    ]
    assert layers.check_c({"firmware/src/odo_odometry.c": {"hal/hal.h"}}) == [
        "upward: firmware/src/odo_odometry.c -> hal/hal.h"
    ]


def test_tools_reach_host_sim_only_through_its_include_folder() -> None:
    v = layers.check_c(
        {
            "tools/ipec/ipec_sim.h": {"host_sim/run/sil.h", "host_sim/include/odosim/odosim_sil.h"},
            "host_sim/cli/odo-sim.c": {"host_sim/src/effects.h"},
            "host_sim/include/odosim/odosim_sil.h": {"host_sim/src/world.h"},
            "host_sim/run/odosim_sil.c": {"host_sim/src/effects.h", "host_sim/run/sil.h"},
        }
    )
    use = " (use host_sim/include)"
    assert sorted(v) == [
        "private: host_sim/cli/odo-sim.c -> host_sim/src/effects.h" + use,
        "private: host_sim/include/odosim/odosim_sil.h -> host_sim/src/world.h" + use,
        "private: tools/ipec/ipec_sim.h -> host_sim/run/sil.h" + use,
    ]


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(text))


def test_includes_resolve_like_the_compiler_and_test_code_is_left_out(tmp_path: Path) -> None:
    _write(
        tmp_path,
        {
            "firmware/include/odo/odo_types.h": "",
            "hal/hal.h": '#include "odo/odo_types.h"\n',
            "hal/sim/hal_sim.h": '#include "hal.h"\n#include "hctl1100.h"\n#include <stdio.h>\n',
            "host_sim/src/hctl1100.h": '#include "odo/odo_types.h"\n',
            "host_sim/src/world.h": '  #  include "hctl1100.h"\n#include "unity.h"\n',
            "host_sim/tests/test_world.c": '#include "world.h"\n#include "tools_only.h"\n',
            "tools/x/tools_only.h": "",
        },
    )
    graph, problems = layers.c_graph(tmp_path)
    assert problems == []
    assert "host_sim/tests/test_world.c" not in graph  # tests may depend on everything
    assert graph["hal/hal.h"] == {"firmware/include/odo/odo_types.h"}
    assert graph["hal/sim/hal_sim.h"] == {"hal/hal.h", "host_sim/src/hctl1100.h"}
    assert graph["host_sim/src/world.h"] == {"host_sim/src/hctl1100.h"}  # unity.h: a system header
    assert layers.check_c(graph) == [
        "upward: hal/sim/hal_sim.h -> host_sim/src/hctl1100.h",
        "private: hal/sim/hal_sim.h -> host_sim/src/hctl1100.h (use host_sim/include)",
    ]


def test_an_ambiguous_header_name_is_reported(tmp_path: Path) -> None:
    _write(
        tmp_path,
        {
            "hal/a/util.h": "",
            "tools/b/util.h": "",
            "hostlib/x.c": '#include "util.h"\n',
        },
    )
    _, problems = layers.c_graph(tmp_path)
    assert problems == ['hostlib/x.c: #include "util.h" is ambiguous: hal/a/util.h, tools/b/util.h']


def test_python_cycles_count_imports_inside_functions(tmp_path: Path) -> None:
    pkg = tmp_path / "odo_tools"
    _write(
        pkg,
        {
            "__init__.py": "",
            "gap/__init__.py": "",
            "gap/diagnose.py": """\
                from .io import read
                def write_report():
                    from .plots import plot_report
                """,
            "gap/plots.py": """\
                import numpy
                def plot_report():
                    from .diagnose import apply
                """,
            "gap/io.py": "import odo_tools.outpath\nfrom odo_tools import resources\n",
            "outpath.py": "",
            "resources.py": "from .gap import io\n",
        },
    )
    graph = layers.py_graph(pkg)
    assert graph["odo_tools.gap.diagnose"] == {"odo_tools.gap.io", "odo_tools.gap.plots"}
    assert graph["odo_tools.gap.plots"] == {"odo_tools.gap.diagnose"}
    assert graph["odo_tools.gap.io"] == {"odo_tools.outpath", "odo_tools.resources"}
    assert graph["odo_tools.resources"] == {"odo_tools.gap.io"}
    assert layers.check_python(graph) == [
        "import cycle: odo_tools.gap.diagnose <-> odo_tools.gap.plots",
        "import cycle: odo_tools.gap.io <-> odo_tools.resources",
    ]


def test_python_imports_for_annotations_only_are_no_dependency(tmp_path: Path) -> None:
    """`if TYPE_CHECKING:` imports never run; an import inside a function beside them does."""
    pkg = tmp_path / "odo_tools"
    _write(
        pkg,
        {
            "__init__.py": "",
            "report.py": """\
                from typing import TYPE_CHECKING
                import typing
                if TYPE_CHECKING:
                    from .diagnose import Dataset
                if typing.TYPE_CHECKING:
                    from . import fit
                def write():
                    from .plots import plot
                """,
            "diagnose.py": "from .report import write\n",
            "fit.py": "from . import report\n",
            "plots.py": """\
                if TYPE_CHECKING:
                    from .report import write
                else:
                    from . import diagnose
                """,
        },
    )
    graph = layers.py_graph(pkg)
    assert graph["odo_tools.report"] == {"odo_tools.plots"}
    assert graph["odo_tools.plots"] == {"odo_tools.diagnose"}
    assert layers.check_python(graph) == [
        "import cycle: odo_tools.diagnose <-> odo_tools.plots <-> odo_tools.report"
    ]


def test_tarjan_finds_every_strongly_connected_component() -> None:
    g = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": {"e"}, "e": {"d"}, "f": {"f", "a"}}
    assert layers.cycles(g) == [["a", "b", "c"], ["d", "e"]]
    assert layers.cycles({"a": {"b"}, "b": set()}) == []


def test_no_target_needs_the_file_with_main_for_a_helper() -> None:
    build = Path(os.environ.get("ODO_BUILD_DIR") or ROOT / "build" / "host")
    graphs = layers.object_graphs(build)
    # odo-ipec and odo-calib are among the targets read: their commands' objects depend one way
    assert graphs["tools/ipec/CMakeFiles/odo-ipec.dir"]["odo-ipec.c.o"] >= {
        "ipec_goals.c.o",
        "ipec_sim.c.o",
    }
    assert "odo-ipec.c.o" not in set().union(*graphs["tools/ipec/CMakeFiles/odo-ipec.dir"].values())
    assert len(graphs) > 10
    assert layers.check_objects(graphs) == []


def test_object_check_finds_a_helper_in_the_main_file(tmp_path: Path) -> None:
    sources = {
        "t/CMakeFiles/tool.dir/main.c": "int cmd(void);\nint helper(void) { return 1; }\n"
        "int main(void) { return cmd(); }\n",
        "t/CMakeFiles/tool.dir/cmd.c": "int helper(void);\nint cmd(void) { return helper(); }\n",
        "t/CMakeFiles/ok.dir/main.c": "int cmd(void);\nint main(void) { return cmd(); }\n",
        "t/CMakeFiles/ok.dir/cmd.c": "int cmd(void) { return 0; }\n",
    }
    for rel, text in sources.items():
        c = tmp_path / rel
        c.parent.mkdir(parents=True, exist_ok=True)
        c.write_text(text)
        subprocess.run(["cc", "-c", str(c), "-o", f"{c}.o"], check=True)
    graphs = layers.object_graphs(tmp_path)
    assert graphs["t/CMakeFiles/ok.dir"] == {"main.c.o": {"cmd.c.o"}, "cmd.c.o": set()}
    assert layers.check_objects(graphs) == [
        "object cycle in t/CMakeFiles/tool.dir: cmd.c.o <-> main.c.o"
    ]
