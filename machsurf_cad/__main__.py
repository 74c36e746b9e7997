"""`python -m machsurf_cad`: the command line (:func:`machsurf_cad._start.entry`)."""

from ._start import entry

entry()
