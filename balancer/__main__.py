"""``python -m balancer``: see :mod:`balancer.cli`."""
import sys

if sys.argv[1:2] == ["run"]:
    # A scene run is short and ends with os._exit (below): its imports (some 10^5 objects, none of
    # them garbage) and stages need no cyclic garbage collection, which would take ~15 ms of the
    # imports made before the plotting process is forked.  The drawing processes run without it too.
    import gc

    gc.disable()
    # the plotting process is forked before anything else is imported: it imports matplotlib (and only the
    # parts of modal that drawing needs) while this process imports the identification toolkit
    # (balancer.scene.plotter; importing balancer.scene loads nothing yet)
    from .scene.plotter import start_early

    start_early()

from .cli import main  # noqa: E402

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
