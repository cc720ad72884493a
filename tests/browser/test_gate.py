"""Without Chromium the browser tests skip with one line locally, and fail in CI (CI=true)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.mark.parametrize("ci, code, word", [("", 0, "skipped"), ("true", 1, "error")])
def test_missing_chromium_skips_locally_and_fails_in_ci(ci, code, word):
    env = {**os.environ, "CHROMIUM": "/nonexistent/chromium", "CI": ci}
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rs",
                          str(HERE / "test_report.py"), "-k", "not_blank and beam"],
                         capture_output=True, text=True, timeout=120, env=env, cwd=HERE.parents[1])
    assert out.returncode == code, out.stdout[-2000:]
    assert word in out.stdout.splitlines()[-1]
    assert "no Chromium: install Debian's chromium" in out.stdout
