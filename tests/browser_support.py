"""Headless Debian Chromium driven by Playwright, for the tests of pages (view, monitor).

Never ``playwright install``: the browser is Debian's package (``make browser`` installs it).
A missing browser fails the tests with that instruction; it never skips them.
"""

from __future__ import annotations

import io
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pytest

CHROMIUM = os.environ.get("MOTIONCUE_CHROMIUM", "/usr/bin/chromium")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@contextmanager
def browser(width: int = 1400, height: int = 720) -> Iterator[Any]:
    """A fresh Chromium context (empty user-data-dir); yields the Playwright context."""
    if not os.path.exists(CHROMIUM):
        pytest.fail(
            f"the browser tests need Debian's chromium at {CHROMIUM}: run `make browser` "
            "(apt-get install chromium) or set MOTIONCUE_CHROMIUM",
            pytrace=False,
        )
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail(
            "the browser tests need the python package playwright: pip install -e '.[dev]'",
            pytrace=False,
        )
    with tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            args=FLAGS,
            headless=True,
            viewport={"width": width, "height": height},
        )
        try:
            yield ctx
        finally:
            ctx.close()


def image_stats(png: bytes) -> tuple[int, float]:
    """``(distinct colours, fraction of pixels that are not near-white)`` of a PNG."""
    import matplotlib.image as mpimg

    img = mpimg.imread(io.BytesIO(png), format="png")[..., :3]
    rgb = np.round(img * 255).astype(np.int64)
    codes = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
    inked = float(np.mean(np.any(rgb < 235, axis=-1)))
    return int(np.unique(codes).size), inked
