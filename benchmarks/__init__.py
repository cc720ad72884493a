"""Benchmarks: run on demand (``python -m benchmarks.<name>``); each prints a table of run time against error."""
