"""Balancing studies fed by modal identification: automatic ball balancer,
slider-crank / compressor counterweight, and machine drive (belt and shaft).

``balancer`` imports ``modal``; never the reverse.
"""
__all__: list[str] = []
