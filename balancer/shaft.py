"""Old import path of :mod:`balancer.drive.shaft` (same module object; see :mod:`balancer._moved`)."""
from balancer._moved import alias

alias(__name__, "balancer.drive.shaft", ("statics", "sizing", "stiffness", "handover"))
