"""Swept envelopes of rotational tools and G1-continuous adjacent passes (numpy only)."""

from .core import Envelope, Motion, fold_check, make_envelope, next_pass, seam_report, tool_segment

__all__ = ["Envelope", "Motion", "make_envelope", "next_pass", "seam_report", "fold_check", "tool_segment"]
