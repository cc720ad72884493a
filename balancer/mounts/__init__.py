"""Old import path of :mod:`balancer.compressor.mounts` (same module object; see :mod:`balancer._moved`).

A package rather than ``mounts.py`` so that git records the move of the old file."""
from balancer._moved import alias

alias(__name__, "balancer.compressor.mounts")
