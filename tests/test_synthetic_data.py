"""The committed synthetic files are what the generator makes (reproducible from the seed)."""
import importlib.util
import re

from support.paths import SYNTHETIC


def test_generator_reproduces_committed_files(tmp_path):
    spec = importlib.util.spec_from_file_location("generate", SYNTHETIC / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    written = generate.main(tmp_path)
    assert written
    for path in written:
        _same_to_rounding(path.read_bytes(), (SYNTHETIC / path.name).read_bytes(), path.name)


#: a number written with 12 or more significant digits by the same generator on another CPU or BLAS build differs
#: in its last digit or two (hammer.csv's samples: 1e-13 relative); a changed generator moves it far more
ROUNDING = 1e-9
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _same_to_rounding(written: bytes, committed: bytes, name: str) -> None:
    """The two files' text equal but for their numbers, which agree to :data:`ROUNDING` relative."""
    assert _NUMBER.split(written) == _NUMBER.split(committed), name
    ours, theirs = _NUMBER.findall(written), _NUMBER.findall(committed)
    assert len(ours) == len(theirs), name
    changed = [(a, b) for a, b in zip(ours, theirs) if a != b]
    assert all(abs(float(a) - float(b)) <= ROUNDING * max(abs(float(a)), abs(float(b))) for a, b in changed), \
        (name, changed[:3])
