"""Helpers shared by the test suites (synthetic time data, a Dask cluster, identified modes, paths)."""
