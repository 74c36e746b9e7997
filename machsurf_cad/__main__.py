"""`python -m machsurf_cad`: the command line (:func:`machsurf_cad._start.entry`)."""

from ._start import entry

if __name__ == "__main__":  # a spawned child process (a large STL's meshing) imports this module again
    entry()
