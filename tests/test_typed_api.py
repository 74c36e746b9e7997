"""Every parameter of every public function is typed (issue 26, item 6): the shared kinds of argument
are the aliases of :mod:`machsurf_cad.typing`."""

from __future__ import annotations

import inspect

import machsurf_cad as ms


def _untyped() -> dict[str, list[str]]:
    """Public function name -> its parameters without an annotation (``*args``/``**kwargs`` aside)."""
    out = {}
    for name in ms.__all__:
        obj = getattr(ms, name)
        if not inspect.isfunction(obj):
            continue
        params = inspect.signature(obj).parameters.values()
        miss = [p.name for p in params if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL) and p.annotation is p.empty]
        if miss:
            out[name] = miss
    return out


def test_every_public_parameter_is_typed():
    n = sum(inspect.isfunction(getattr(ms, name)) for name in ms.__all__)
    assert n > 30  # the scan saw the API's functions, not an empty list
    untyped = _untyped()
    assert not untyped, "untyped parameters of public functions: " + "; ".join(
        f"{name}({', '.join(params)})" for name, params in sorted(untyped.items())
    )
