"""Cut simulation (N-buffer) and passes spaced by a scallop height (mm, degrees)."""

from .api import DEFAULT_HEIGHTS_MM, SimulationResult, sample_faces, simulate

__all__ = ["simulate", "SimulationResult", "sample_faces", "DEFAULT_HEIGHTS_MM"]
