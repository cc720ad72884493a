"""Old import path of :mod:`balancer.drive.report` (same module object; see :mod:`balancer._moved`).

A package rather than ``drive_report.py`` so that git records the move of the old file."""
from balancer._moved import alias

alias(__name__, "balancer.drive.report")
