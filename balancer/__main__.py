"""``python -m balancer``: see :mod:`balancer.cli`."""
import sys

from .cli import main

code = main()
if sys.argv[1:2] == ["run"]:
    # A scene run has written its archive and plots (atomically), closed its files and waited for its
    # drawing processes: the interpreter's teardown (~60 ms collecting the objects of some 300 modules,
    # a sixth of the run) would change nothing.  Flush what was printed and leave at once.
    import os

    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)
sys.exit(code)
