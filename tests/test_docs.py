"""Issue 14 item 5: the documentation site is built by the test command, warnings as errors.

Sphinx (MyST pages, autodoc + numpydoc API reference) into a temporary folder: a broken page,
a bad link between pages or a docstring Sphinx cannot read fails the suite.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


@pytest.mark.timeout(300)
def test_docs_build_with_warnings_as_errors(tmp_path: Path) -> None:
    out = tmp_path / "html"
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, timeout=280,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    )  # fmt: skip
    elapsed = time.perf_counter() - t0
    assert proc.returncode == 0, proc.stderr[-4000:]
    pages = {p.relative_to(out).as_posix() for p in out.rglob("*.html")}
    for page in ("index.html", "pipeline.html", "conventions.html", "formats.html", "api.html",
                 "tutorials/rig-owner.html", "tutorials/seat-maker.html",
                 "tutorials/researcher.html", "cue-metrics.html"):  # fmt: skip
        assert page in pages, sorted(pages)
    api = (out / "api.html").read_text(encoding="utf-8")
    # the reference documents each stage's public names (spot checks from every subpackage)
    for name in ("motioncue.kinematics.load_platform", "motioncue.cueing.load_cueing",
                 "motioncue.pipeline.load_ride", "motioncue.output.load_controller",
                 "motioncue.telemetry.open_source", "motioncue.trajectory.ActuatorLimits",
                 "motioncue.ConfigError", "motioncue.cueing.cue_metrics",
                 "motioncue.cueing.cue_bound"):  # fmt: skip
        assert f'id="{name}"' in api, name
    print(f"docs built in {elapsed:.1f} s")


def test_conventions_cited_by_docstrings_are_in_the_repository() -> None:
    cited = []
    for path in (ROOT / "src" / "motioncue").rglob("*.py"):
        for m in re.finditer(r"(docs/)?conventions\.md", path.read_text(encoding="utf-8")):
            cited.append((path.name, m.group(0)))
    assert cited, "no docstring cites the conventions"
    text = (DOCS / "conventions.md").read_text(encoding="utf-8")
    # the project's copy covers what the citations rely on
    for topic in ("x forward, y left, z up", "R = Rz(yaw) Ry(pitch) Rx(roll)", "f = a - g",
                  "udp://HOST:PORT", "numbered from 1"):  # fmt: skip
        assert topic in text, topic
