"""Benchmarks: machsurf_cad's vectorised numpy against OCCT (or brute force) in the same run."""
