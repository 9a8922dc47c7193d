"""Write the drives of ``configs/recordings/generated.toml`` (not bundled) into a folder.

Each entry's command (``tools/make_sample_lap.py`` with a seed) is run in-process with its
``--out`` replaced by the folder, so the files are those the command writes (to the last
written decimal on another machine's floats, as the bundled drives). A file already there
with the same text is left alone.

Usage::

    python tools/make_generated_drives.py                  # every drive, into build/drives/
    python tools/make_generated_drives.py --set held-out   # the six fresh held-out drives
    python tools/make_generated_drives.py --out /tmp/d --set tuning

Tests use :func:`generated_drives`; the search tools take the written paths.
"""

from __future__ import annotations

import argparse
import importlib.util
import shlex
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from motioncue._atomic import atomic_write_bytes  # noqa: E402
from motioncue._errors import ConfigError  # noqa: E402
from motioncue.telemetry import sample_drive_manifest  # noqa: E402
from motioncue.telemetry._drives import DRIVE_SETS, SampleDrive  # noqa: E402

MANIFEST = ROOT / "configs" / "recordings" / "generated.toml"
DEFAULT_OUT = ROOT / "build" / "drives"


def _generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "make_sample_lap_gen", ROOT / "tools/make_sample_lap.py"
    )
    if spec is None or spec.loader is None:
        raise ConfigError("tools/make_sample_lap.py cannot be loaded")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def generator_argv(drive: SampleDrive) -> list[str]:
    """The arguments of ``drive``'s command after the script name, ``--out`` at ``drive.path``.

    Raises
    ------
    ConfigError
        A command that is not ``python tools/make_sample_lap.py ... --out build/drives/FILE``.
    """
    argv = shlex.split(drive.command)
    if argv[:2] != ["python", "tools/make_sample_lap.py"] or "--out" not in argv:
        raise ConfigError(f"{drive.name}: command {drive.command!r} is not make_sample_lap --out")
    i = argv.index("--out")
    if i + 1 >= len(argv) or argv[i + 1] != f"build/drives/{drive.path.name}":
        raise ConfigError(f"{drive.name}: --out must be build/drives/{drive.path.name}")
    return [*argv[2 : i + 1], str(drive.path), *argv[i + 2 :]]


def generated_drives(
    out: str | Path = DEFAULT_OUT, set: str | None = None, kind: str | None = None
) -> list[Path]:
    """Write the generated drives of ``set`` (and ``kind``) into ``out``; their paths, in
    manifest order. A file already holding the command's text is not rewritten."""
    if set is not None and set not in DRIVE_SETS:
        raise ConfigError(f"drive set {set!r} is unknown; allowed: {', '.join(DRIVE_SETS)}")
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    tool = None
    paths = []
    for drive in sample_drive_manifest(folder, manifest=MANIFEST):
        if (set is not None and drive.set != set) or (kind is not None and drive.kind != kind):
            continue
        tool = tool or _generator()
        text = tool.drive_csv_text(generator_argv(drive))
        if not (drive.path.exists() and drive.path.read_text() == text):
            atomic_write_bytes(drive.path, text.encode(), "generated drive")  # never half-written
        paths.append(drive.path)
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="folder (default build/drives)")
    ap.add_argument("--set", choices=DRIVE_SETS, default=None, help="only this set")
    args = ap.parse_args(argv)
    for path in generated_drives(args.out, args.set):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
