"""The committed synthetic files are what the generator makes (reproducible from the seed)."""
import importlib.util

from support.paths import SYNTHETIC


def test_generator_reproduces_committed_files(tmp_path):
    spec = importlib.util.spec_from_file_location("generate", SYNTHETIC / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    written = generate.main(tmp_path)
    assert written
    for path in written:
        assert path.read_bytes() == (SYNTHETIC / path.name).read_bytes(), path.name
