"""Content keys: hashes of what a result is computed from (faces, arrays, parameters), so that a cache
reuses a result only for the very same input (:mod:`machsurf_cad.threeaxis.cache`, :func:`machsurf_cad.verify`).
"""

from __future__ import annotations

import hashlib

import numpy as np


def _update_array(h, a) -> None:
    a = np.ascontiguousarray(np.asarray(a))
    h.update(str((a.dtype.str, a.shape)).encode())
    h.update(a.tobytes())


def faces_key(faces) -> str:
    """A hash of the faces' geometry, trimming and names (what a face set is built from)."""
    from .geometry.bspline import BSplineSurface
    from .geometry.face import Face

    h = hashlib.sha256()
    for f in faces:
        face = Face(f, name=f.name) if isinstance(f, BSplineSurface) else f
        if not isinstance(face, Face):
            return ""  # not faces: no key (face_set refuses them with its own message)
        s = face.surface
        h.update(repr((type(face).__name__, face.name, s.degree_u, s.degree_v, s.periodic_u, s.periodic_v,
                       face.uv_bounds, face.reversed)).encode())  # fmt: skip
        for a in (s.knots_u, s.mults_u, s.knots_v, s.mults_v, s.poles, np.zeros(0) if s.weights is None else s.weights):
            _update_array(h, a)
        for loop in face.loops:
            h.update(b"loop")
            for c in loop:
                h.update(repr((c.degree, c.periodic)).encode())
                for a in (c.knots, c.mults, c.poles, np.zeros(0) if c.weights is None else c.weights):
                    _update_array(h, a)
    return h.hexdigest()


def content_key(*parts) -> str:
    """A hash of arrays (dtype, shape and bytes) and other values (their ``repr``)."""
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            _update_array(h, p)
        else:
            h.update(repr(p).encode())
            h.update(b"\0")
    return h.hexdigest()
