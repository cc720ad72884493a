"""``python -m balancer``: see :mod:`balancer.cli`."""
import sys

from .cli import main

sys.exit(main())
