"""The version of machsurf_cad: its one source (pyproject reads it; a test checks package.xml)."""

__version__ = "0.3.0"
