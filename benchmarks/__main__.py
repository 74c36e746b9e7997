"""Run all benchmarks and print one table (``python -m benchmarks`` or ``make bench``).

Options: ``--quick`` (smaller sizes), ``--json PATH`` (write the rows).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys

from . import (
    bench_avoid,
    bench_batch,
    bench_dropcutter,
    bench_envelope,
    bench_eval,
    bench_flank,
    bench_freecad,
    bench_offset,
    bench_reff,
    bench_simulate,
    bench_step,
    bench_verify,
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks")
    ap.add_argument("--quick", action="store_true", help="10x fewer points")
    ap.add_argument("--json", default=None, help="write the rows to this JSON file")
    args = ap.parse_args(argv)
    rows = []
    for bench in bench_eval.BENCHMARKS:
        rows.append(bench(quick=args.quick))
        _print_row(rows[-1], header=len(rows) == 1)
    # row producers, each followed by its footnote
    for produce, note in (
        (bench_reff.reff_rows, "* per-point OCCT time measured on a 256^2 sub-grid and scaled to the full grid"),
        (
            bench_envelope.envelope_rows,
            "* brute force: 10 positions measured (2000 x 400 points each) and scaled to 200",
        ),
        (bench_flank.flank_rows, None),
        (bench_verify.verify_rows, None),
        (bench_step.step_rows, None),
        (bench_simulate.simulate_rows, "* brute force on a random subset of the finest samples, scaled to all samples"),
        (bench_batch.batch_rows, None),
        (
            bench_freecad.freecad_rows,
            "* FreeCAD: the CAM operation's raster in FreeCADCmd (kernel cached), "
            "reference = the same raster and check through the API here; max diff = |max gouge there - here|",
        ),
        (
            bench_avoid.avoid_rows,
            "* avoidance: time per position in the report (ms_per_position); reference = the "
            "whole-part check of the path it wrote (max diff = that check's max gouge)",
        ),
        (
            bench_dropcutter.dropcutter_rows,
            "* drop-cutter: OpenCAMLib on an OCCT mesh of the same STEP (deflection 0.001 mm), speed-up = CPU time "
            "ratio; max diff = |ours - OpenCAMLib|: ours is higher by the mesh's sag at most, lower only on grid "
            "lines exactly R from a wall (OpenCAMLib lets the wall touching the tool's side lift it); the raster "
            "row compares with the verify of the path it wrote (max diff = its max gouge)",
        ),
    ):
        for row in produce(quick=args.quick):
            rows.append(row)
            _print_row(row, header=False)
        if note:
            print(note)
    iso_rows = bench_simulate.isoscallop_rows(quick=args.quick)
    bench_simulate.print_iso(iso_rows)
    offset_rows = bench_offset.offset_fit_rows(quick=args.quick)
    bench_offset.print_rows(offset_rows)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(
                {
                    "python": sys.version.split()[0],
                    "machine": platform.machine(),
                    "rows": rows,
                    "offset_fit": offset_rows,
                    "iso_scallop": iso_rows,
                },
                fh,
                indent=2,
            )
    return 0


def _print_row(r, header):
    if header:
        print(
            f"{'benchmark':<46} {'n':>9} {'machsurf s':>11} {'reference s':>12} {'reference':<22} {'speed-up':>9} "
            f"{'max diff':>10}"
        )
        print("-" * 126)
    print(
        f"{r['name']:<46} {r['n']:>9} {r['ours_s']:>11.3f} {r['ref_s']:>12.3f} {r['ref']:<22} "
        f"{r.get('cpu_ratio', r['ref_s'] / r['ours_s']):>8.1f}x {r['max_diff']:>10.2e}",
        flush=True,
    )


if __name__ == "__main__":
    sys.exit(main())
