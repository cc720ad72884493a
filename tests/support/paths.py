"""Where the project's own files are, for tests in any folder."""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SYNTHETIC = ROOT / "data" / "synthetic"
#: real measured files shipped with the project (MIT, from ladisk/pyuff; see data/real/README.md)
REAL = ROOT / "data" / "real"
