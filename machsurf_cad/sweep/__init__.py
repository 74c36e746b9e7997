"""Swept envelopes of rotational tools and G1-continuous adjacent passes (numpy only)."""

from .api import Continuity, EnvelopeResult, chain_toolpath, envelope, fitted_normals
from .core import Envelope, Motion, fold_check, make_envelope, next_pass, seam_report, tool_segment
from .passes import PassChain, build_chain, max_theta
from .pathfile import load_path

__all__ = [
    "Envelope",
    "Motion",
    "make_envelope",
    "next_pass",
    "seam_report",
    "fold_check",
    "tool_segment",
    "envelope",
    "EnvelopeResult",
    "chain_toolpath",
    "fitted_normals",
    "Continuity",
    "PassChain",
    "build_chain",
    "max_theta",
    "load_path",
]
