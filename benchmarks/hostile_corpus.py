"""A hostile corpus over every command: bad numbers, bad files, output folders holding a user's file.

``python -m benchmarks.hostile_corpus [--jobs 2] [--limit-s 90] [--json out.json]`` builds the cases
from the command line's own parser (every option of every command gets ``nan``, ``inf``, ``-1``, ``0``,
``1e300``, ``abc`` or, for text options, ``""`` and ``???``), adds bad input files (missing, empty,
binary, a folder, UTF-16, a text file named .step, an STL as a part) and output folders (holding a
user's file, a file, the current folder), and runs each in a forked child of a process that has already
imported the package (so a case costs its work, not the imports) under a time limit.

Each case is judged on what can be judged without knowing the right figure:

- ``traceback``: "Traceback" on stderr, or an exit code other than 0, 1 or 2;
- ``not one line``: exit 1 with other than one line on stderr (usage lines aside);
- ``silently wrong``: a value that must be refused (``nan``, ``inf``, ``abc``, a file that is not what
  the option needs, a folder holding a user's file) that was not (exit 0 or 2);
- ``half-written``: a ``.partial-`` or ``.old-`` folder left, or an output folder after exit 1;
- ``user file lost``: the user's file in the output folder gone or changed;
- ``hang``: not finished within the time limit (killed).

It prints the tally and the cases of each defect.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLOCK = ROOT / "example_parts" / "freeform_block.step"

BASE = {  # a fast valid command line per command
    "info": [str(BLOCK)],
    "inspect": [str(BLOCK), str(BLOCK), "--samples", "20", "--no-render"],
    "machining-surface": ["--example", "bezier5", "--tool", "ball:D=10", "--axes", "3", "--tolerance", "0.01"],
    "reff": ["--example", "bezier5", "--tool", "bull:D=10,r=2", "--grid", "16", "--no-render"],
    "flank": ["--example", "hypar", "--tool", "cyl:D=20", "--no-render"],
    "envelope": ["--example", "line", "--tool", "cyl:D=10", "--passes", "1", "--no-render"],
    "verify": [str(BLOCK), "--toolpath", "{csv}", "--no-render"],
    "simulate": [str(BLOCK), "--toolpath", "{csv}", "--resolution", "2", "--no-render"],
}
MUST_REFUSE = {"nan", "inf", "-inf", "abc", "???"}


def _options():
    """(command, option, kind) for every option of every command, from the CLI's parser."""
    from machsurf_cad.cliargs import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for cmd, p in sub.choices.items():
        if cmd not in BASE:
            continue
        for a in p._actions:
            if not a.option_strings or a.option_strings[0] in ("-h", "-o"):
                continue
            opt = max(a.option_strings, key=len)
            if a.nargs == 0:
                continue
            kind = "number" if a.type is not None and a.type is not str else "text"
            out.append((cmd, opt, kind))
    return out


def _with(argv: list[str], opt: str, value: str) -> list[str]:
    """``argv`` with ``opt`` set to ``value`` (replacing it when present)."""
    argv = list(argv)
    if opt in argv:
        i = argv.index(opt)
        del argv[i : i + 2]
    return argv + [f"{opt}={value}"]


def build_cases(work: Path) -> list[dict]:
    """Every case: name, argv (output folder last), what must happen."""
    cases = []
    for cmd, opt, kind in _options():
        values = ["nan", "inf", "-1", "0", "1e300", "abc"] if kind == "number" else ["", "???", "-1"]
        for v in values:
            cases.append(
                {"name": f"{cmd} {opt}={v!r}", "argv": [cmd, *_with(BASE[cmd], opt, v)], "refuse": v in MUST_REFUSE}
            )
    files = _bad_files(work)
    for name, path in files.items():
        for cmd in ("info", "inspect", "machining-surface", "verify", "simulate"):
            argv = {"info": [cmd, path], "inspect": [cmd, path, str(BLOCK)],
                    "machining-surface": [cmd, path, "--tool", "ball:D=10", "--axes", "3"],
                    "verify": [cmd, path, "--toolpath", "{csv}"],
                    "simulate": [cmd, path, "--toolpath", "{csv}"]}[cmd]  # fmt: skip
            cases.append({"name": f"{cmd} part={name}", "argv": argv, "refuse": True})
        for cmd in ("verify", "simulate"):
            cases.append({"name": f"{cmd} toolpath={name}", "argv": [cmd, str(BLOCK), "--toolpath", path,
                          "--tool", "ball:D=10"], "refuse": name != "utf16.csv"})  # a valid x,y,z path  # fmt: skip
    for cmd in BASE:
        for where in ("user", "file", "cwd"):
            cases.append({"name": f"{cmd} -o {where}", "argv": [cmd, *BASE[cmd]], "out": where, "refuse": True})
    return cases


def _bad_files(work: Path) -> dict[str, str]:
    d = work / "inputs"
    d.mkdir()
    (d / "empty.step").write_bytes(b"")
    (d / "binary.step").write_bytes(bytes(range(256)) * 64)
    (d / "text.step").write_text("this is not STEP\n")
    (d / "utf16.step").write_text("ISO-10303-21;\nEND-ISO-10303-21;\n", encoding="utf-16")
    (d / "folder.step").mkdir()
    (d / "truncated.step").write_bytes(BLOCK.read_bytes()[:3000])
    (d / "garbage.csv").write_bytes(bytes(range(256)) * 8)
    (d / "utf16.csv").write_text("x,y,z\n1,2,3\n", encoding="utf-16")
    (d / "nocols.csv").write_text("a,b\n1,2\n")
    return {p.name: str(p) for p in sorted(d.iterdir())} | {"missing.step": str(d / "missing.step")}


def _run_case(case: dict, folder: Path) -> tuple[int, str]:
    """Fork a child running the case with stdout/err to files; returns (exit code or -signal, stderr)."""
    out = folder / "out"
    argv = [a.replace("{csv}", str(folder.parent / "path.csv")) for a in case["argv"]]
    where = case.get("out")
    cwd = folder
    if where == "user":
        out.mkdir()
        (out / "thesis.txt").write_text("mine")
    elif where == "file":
        out.write_text("mine")
    elif where == "cwd":
        out.mkdir()
        (out / "thesis.txt").write_text("mine")
        cwd = out
    argv += ["-o", "." if where == "cwd" else str(out)]
    err = folder / "stderr.txt"
    pid = os.fork()
    if pid == 0:  # the child: run the command as the console script does
        os.chdir(cwd)
        fd = os.open(str(err), os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(fd, 2)
        nul = os.open(os.devnull, os.O_WRONLY)
        os.dup2(nul, 1)
        os.setpgid(0, 0)
        code = 99
        try:
            from machsurf_cad._start import main

            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors: what the console script turns into the exit code
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException:  # an escaped exception is a traceback
            import traceback

            traceback.print_exc()
            code = 98
        finally:
            os._exit(code if isinstance(code, int) else 97)
    return pid, str(err)


def judge(case: dict, code: int, stderr: str, folder: Path) -> list[str]:
    out = folder / "out"
    bad = []
    if "Traceback" in stderr or code not in (0, 1, 2):
        bad.append("traceback")
    lines = [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("usage:") and not ln.startswith(" ")]
    if code == 1 and len([ln for ln in lines if ln.startswith("machsurf")]) != 1:
        bad.append("not one line")
    if case["refuse"] and code in (0, 2):
        bad.append("silently wrong")
    left = [p.name for p in folder.rglob("*") if ".partial-" in p.name or ".old-" in p.name]
    if left or (code == 1 and case.get("out") is None and out.exists()):
        bad.append("half-written")
    where = case.get("out")
    if where in ("user", "cwd") and not ((out / "thesis.txt").is_file() and (out / "thesis.txt").read_text() == "mine"):
        bad.append("user file lost")
    if where == "file" and not (out.is_file() and out.read_text() == "mine"):
        bad.append("user file lost")
    return bad


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--limit-s", type=float, default=90.0)
    ap.add_argument("--json", default=None)
    ap.add_argument("--only", default=None, help="run only cases whose name contains this")
    args = ap.parse_args(argv)
    import numpy as np  # noqa: F401  (imported once in the parent: children are forked)

    import machsurf_cad as ms
    import machsurf_cad.cli
    import machsurf_cad.occ

    work = Path(tempfile.mkdtemp(prefix="machsurf-hostile-"))
    face = ms.example("bezier5")
    res = ms.machining_surface(ms.occ.read_step_face(str(BLOCK), 0), "ball:D=10", axes=3, tolerance=1e-2)
    ms.write_csv(work / "path.csv", ms.tool_paths(res, stepover=20.0))
    del face
    cases = build_cases(work)
    if args.only:
        cases = [c for c in cases if args.only in c["name"]]
    print(f"{len(cases)} cases, {args.jobs} at a time, {args.limit_s:g} s each at most", flush=True)
    running: dict[int, tuple] = {}
    results = []
    todo = list(enumerate(cases))
    t0 = time.perf_counter()
    while todo or running:
        while todo and len(running) < args.jobs:
            i, case = todo.pop(0)
            folder = work / f"case{i:04d}"
            folder.mkdir()
            pid, err = _run_case(case, folder)
            running[pid] = (i, case, folder, err, time.perf_counter())
        for pid, (_i, case, folder, err, start) in list(running.items()):
            done, status = os.waitpid(pid, os.WNOHANG)
            hung = not done and time.perf_counter() - start > args.limit_s
            if hung:
                os.killpg(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            if done or hung:
                code = os.waitstatus_to_exitcode(status) if done else -9
                stderr = Path(err).read_text(errors="replace") if Path(err).exists() else ""
                bad = ["hang"] if hung else judge(case, code, stderr, folder)
                results.append({"case": case["name"], "exit_code": code, "defects": bad,
                                "time_s": round(time.perf_counter() - start, 2),
                                "stderr": stderr.strip().splitlines()[-1:] if stderr.strip() else []})  # fmt: skip
                del running[pid]
                shutil.rmtree(folder, ignore_errors=True)
        time.sleep(0.02)
    kinds = ["traceback", "not one line", "silently wrong", "half-written", "user file lost", "hang"]
    tally = {k: sum(k in r["defects"] for r in results) for k in kinds}
    print(f"{len(results)} cases in {time.perf_counter() - t0:.0f} s")
    for k in kinds:
        print(f"  {k:15s} {tally[k]}")
        for r in results:
            if k in r["defects"]:
                print(f"      {r['case']}: exit {r['exit_code']} {r['stderr']}")
    if args.json:
        Path(args.json).write_text(json.dumps({"tally": tally, "n_cases": len(results), "cases": results}, indent=1))
    shutil.rmtree(work, ignore_errors=True)
    return 0 if not any(tally.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
