"""The version of machsurf_cad: its one source (pyproject reads it; a test checks the workbench package.xml)."""

__version__ = "0.2.0"
