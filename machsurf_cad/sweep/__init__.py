"""Swept envelopes of rotational tools and G1-continuous adjacent passes (numpy only)."""

from .core import Envelope, Motion, fold_check, make_envelope, next_pass, seam_report, tool_segment

__all__ = ["Envelope", "Motion", "make_envelope", "next_pass", "seam_report", "fold_check", "tool_segment"]


def envelope(tool, motion, *, passes: int = 1, continuity: str = "g1", theta_deg=0.0, tolerance: float = 1e-3,
             side: int = 1):
    """Python form of ``machsurf envelope``: ``passes`` envelopes of ``tool`` (str or Cutter) along
    ``motion`` (a :class:`Motion`), chained G1/G0, each fitted within ``tolerance`` (mm).
    Returns a :class:`~machsurf_cad.sweep.passes.PassChain` (``.report()`` for the figures)."""
    from .passes import build_chain

    return build_chain(make_envelope(motion, tool, side=side), passes, continuity=continuity, theta_deg=theta_deg,
                       tolerance=tolerance)


__all__ += ["envelope"]
