"""Every public function of the compressor study documents each of its parameters (numpydoc)."""
from __future__ import annotations

from balancer.compressor import crank


def test_every_public_parameter_is_documented():
    # numpydoc discipline, without a numpydoc dependency
    import inspect
    import re

    from balancer.compressor import crank_plots, mounts

    missing = []
    for module in (crank, mounts, crank_plots):
        for name in module.__all__:
            obj = getattr(module, name)
            if not callable(obj):
                continue
            doc = inspect.getdoc(obj) or ""
            missing += [f"{module.__name__}.{name}({p})" for p in inspect.signature(obj).parameters
                        if not re.search(rf"\b{p}\b", doc)]
    assert missing == []
