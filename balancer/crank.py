"""Old import path of :mod:`balancer.compressor.crank` (same module object; see :mod:`balancer._moved`)."""
from balancer._moved import alias

alias(__name__, "balancer.compressor.crank", ("model", "forces", "counterweight"))
