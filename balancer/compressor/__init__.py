"""Compressor study: the slider-crank and its counterweight, the body on its mounts.

* :mod:`balancer.compressor.crank`: shaking forces and the optimal counterweight;
* :mod:`balancer.compressor.mounts`: the compressor body as a rigid body on
  elastic mounts, forced by the shaking harmonics;
* :mod:`balancer.compressor.crank_plots`: plots of the above (matplotlib; imported
  on demand).
"""
