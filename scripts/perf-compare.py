#!/usr/bin/env python3
"""Time trackfix against plain-text baselines on generated programs, in one run.

    python3 scripts/perf-compare.py [--bin NAME=PATH ...] [--sizes 20] [--krl-mb 34] [--runs 3]

Generates (once, under --work, default /tmp/trackfix-perf) a RobotStudio-style RAPID module of
the benches' shape (robtargets with eax_a, MoveL/Offs lines, comments, CRLF) per size in --sizes
and a KUKA.Sim-style .src/.dat pair of about --krl-mb MB, then times, per input:

  grep -c robtarget (E6POS for KRL)     the plain text scan `check` is held against
  benches/regex_baseline.py             a regex rewrite of every robtarget (RAPID only)
  examples/robtarget_scan.rs            the least a program does that reads every robtarget's
                                        numbers (RAPID only; when built: `cargo build --release
                                        --example robtarget_scan`)
  trackfix check / correct / inspect --format json   for every --bin given

`correct` uses samples/cell.toml without robot r1's arm (see bench_cell), so it corrects and
writes every target, into a new empty folder each run.

CPU time (user + sys of the child, from os.wait4) is the median of --runs runs; peak memory is
the child's maximum resident set. Output goes to a scratch folder and file. Give two
binaries (--bin before=/tmp/trackfix-before --bin after=target/release/trackfix) to compare
builds in the same run, their runs of each command taken in turn; the machine's load average
is printed with the table.
"""

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CELL = os.path.join(ROOT, "samples", "cell.toml")


def rapid_module(mb: float) -> bytes:
    """The shape of benches/rapid_parse.rs `module`: declarations first, then one routine."""
    target = int(mb * 1_000_000)
    decls = [
        "%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n\r\nMODULE Bench\r\n",
        "  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\r\n",
        '  TASK PERS wobjdata wCar:=[FALSE,TRUE,"",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[1,0,0,0]]];\r\n',
    ]
    moves = ["  PROC main()\r\n"]
    size = sum(map(len, decls)) + len(moves[0])
    i = 0
    while size < target:
        s = 150.0 + (i % 7700)
        x = s - 1670.3 + (i % 37) * 0.37
        d = (
            f"  CONST robtarget p{i}:=[[{x:.2f},-{700.0 + (i % 13):.2f},{250.0 + (i % 29) * 12.5:.2f}],"
            f"[0.000000,0.707107,0.707107,0.000000],[0,0,-1,0],[{s:.1f},9E+09,9E+09,9E+09,9E+09,9E+09]];\r\n"
        )
        m = ""
        if i % 10 == 0:
            m += f"    ! group {i // 10}\r\n    MoveL Offs(p{i},0,0,100), v1000, z10, tGun\\WObj:=wCar;\r\n"
        m += f"    MoveL p{i}, v1000, z10, tGun\\WObj:=wCar;\r\n"
        decls.append(d)
        moves.append(m)
        size += len(d) + len(m)
        i += 1
    moves.append("  ENDPROC\r\nENDMODULE")
    return ("".join(decls) + "".join(moves)).encode()


def krl_pair(mb: float) -> tuple[bytes, bytes]:
    """The shape of benches/krl_parse.rs: E6POS/FDAT/LDAT declarations and inline forms."""
    target = int(mb * 1_000_000)
    dat = ["&ACCESS RVP\r\n&REL 1\r\nDEFDAT bench PUBLIC\r\n"]
    src = ["&ACCESS RVP\r\n&REL 1\r\nDEF bench( )\r\n"]
    size = len(dat[0]) + len(src[0])
    i = 0
    while size < target:
        i += 1
        e1 = 100.0 + (i % 7800)
        d = (
            f"DECL E6POS XP{i}={{X {1200.0 + i * 0.25:.3f},Y {-800.0 + (i % 100):.3f},Z 1020.500,"
            f"A -178.2500,B 12.5000,C 179.4000,S 6,T 50,E1 {e1:.3f},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}\r\n"
            f'DECL FDAT FP{i}={{TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE,POINT2[] " ",TQ_STATE FALSE}}\r\n'
            f"DECL LDAT LCPDAT{i}={{VEL 2.0,ACC 100.0,APO_DIST 100.0,APO_FAC 50.0,ORI_TYP #VAR,CIRC_TYP #BASE}}\r\n"
        )
        s = (
            f";FOLD LIN P{i} CONT Vel=2 m/s CPDAT{i} Tool[1]:gun1 Base[1]:car;%{{PE}}%R 8.3.31,"
            f"%MKUKATPBASIS,%CMOVE,%VLIN,%P 1:LIN, 2:P{i}, 3:C_DIS C_DIS, 5:2, 7:CPDAT{i}\r\n"
            f"$BWDSTART=FALSE\r\nLDAT_ACT=LCPDAT{i}\r\nFDAT_ACT=FP{i}\r\nBAS(#CP_PARAMS,2)\r\n"
            f"LIN XP{i} C_DIS C_DIS\r\n;ENDFOLD\r\n"
        )
        dat.append(d)
        src.append(s)
        size += len(d) + len(s)
    dat.append("ENDDAT\r\n")
    src.append("END\r\n")
    return "".join(src).encode(), "".join(dat).encode()


def bench_cell(work: str) -> str:
    """samples/cell.toml without robot r1's kinematics, written under `work`.

    With r1's arm the transforms check every target's reach, and the generated targets' written
    configuration is not the one the arm reaches them with: `correct` would refuse all of them
    and write nothing (exit 3). Without the arm it corrects and writes every target, the work
    the regex script is compared with. Relative paths are made absolute (the copy lives
    elsewhere).
    """
    samples = os.path.join(ROOT, "samples")
    with open(CELL, encoding="utf-8") as f:
        text = f.read()
    text = text.replace('profile = "track/', f'profile = "{samples}/track/')
    text = text.replace('config_dat = "krl/', f'config_dat = "{samples}/krl/')
    arm = '[robot.r1.kinematics]\nmodel = "abb_irb4600_40_255"\n'
    if arm not in text:
        sys.exit(f"{CELL}: no [robot.r1.kinematics] table as expected; update bench_cell")
    path = os.path.join(work, "cell-no-arm.toml")
    with open(path, "w", encoding="utf-8") as f:
        f.write(text.replace(arm, ""))
    return path


def write_once(path: str, make) -> None:
    if not os.path.exists(path):
        data = make()
        with open(path + ".part", "wb") as f:
            f.write(data)
        os.replace(path + ".part", path)


SCAN = os.path.join(ROOT, "target", "release", "examples", "robtarget_scan")
TIME = "/usr/bin/time" if os.path.exists("/usr/bin/time") else None


def run(argv: list[str]) -> tuple[float, int, int]:
    """CPU seconds, peak RSS in bytes and exit code of one child.

    Through /usr/bin/time when present: a child forked from this Python process would report
    the interpreter's resident pages, copied at fork, as its own peak. Output goes to a scratch
    file, not /dev/null: GNU grep stops at the first match when it sees /dev/null.
    """
    with tempfile.NamedTemporaryFile("r") as report, tempfile.TemporaryFile() as sink:
        wrapped = [TIME, "-f", "%M", "-o", report.name, *argv] if TIME else argv
        p = subprocess.Popen(wrapped, stdout=sink, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(p.pid, 0)
        err = p.stderr.read()
        p.stderr.close()
        code = os.waitstatus_to_exitcode(status)
        # wait4 counts the children a child reaped (time's command), in microseconds; time's
        # own `%U %S` has only 10 ms steps. ru_maxrss is in KiB on Linux.
        cpu = usage.ru_utime + usage.ru_stime
        peak = int(report.read().split()[-1]) * 1024 if TIME else usage.ru_maxrss * 1024
    if code not in (0, 1):
        sys.exit(f"{' '.join(argv)} failed with {code}:\n{err.decode(errors='replace')}")
    return cpu, peak, code


OUT = "{out}"


def measure(argv: list[str], runs: int, work: str = "") -> tuple[float, int]:
    """Median CPU time and largest peak of `runs` runs. An argument `OUT` becomes a new, empty
    folder under `work` for each run: `correct` into a folder that already holds its outputs
    first reads them (to restore them if the run fails), which is not the run being measured."""
    return measure_alternating([argv], runs, work)[0]


def measure_alternating(argvs: list[list[str]], runs: int, work: str = "") -> list[tuple[float, int]]:
    """`measure` of each command line, their runs taken in turn (one of each, then the next of
    each): on a shared machine the load drifts within a minute, and runs of one binary after
    the other's moved the CPU times of the same instructions by a third."""
    results: list[list[tuple[float, int, int]]] = [[] for _ in argvs]
    for _ in range(runs):
        for argv, out_of in zip(argvs, results):
            out = tempfile.mkdtemp(prefix="out-", dir=work or None) if OUT in argv else None
            try:
                out_of.append(run([out if a == OUT else a for a in argv]))
            finally:
                if out:
                    shutil.rmtree(out)
    return [(statistics.median(r[0] for r in rs), max(r[1] for r in rs)) for rs in results]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", action="append", default=[], help="NAME=PATH of a trackfix binary (repeatable)")
    ap.add_argument("--sizes", default="20", help="RAPID module sizes in MB, comma-separated (e.g. 1,10,100)")
    ap.add_argument("--krl-mb", type=float, default=34, help="KRL pair size in MB (0: none)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "trackfix-perf"))
    args = ap.parse_args()
    bins = [b.split("=", 1) for b in args.bin] or [["trackfix", os.path.join(ROOT, "target/release/trackfix")]]
    os.makedirs(args.work, exist_ok=True)
    out_dir = os.path.join(args.work, "out")
    os.makedirs(out_dir, exist_ok=True)
    cell = bench_cell(args.work)

    inputs = []  # (label, file to pass, bytes, grep pattern, file grep reads, is rapid)
    for mb in [float(s) for s in args.sizes.split(",") if s]:
        path = os.path.join(args.work, f"bench_{mb:g}mb.mod")
        write_once(path, lambda: rapid_module(mb))
        inputs.append((f"RAPID {mb:g} MB", path, os.path.getsize(path), "robtarget", path, True))
    if args.krl_mb > 0:
        src_path = os.path.join(args.work, f"bench_{args.krl_mb:g}mb.src")
        dat_path = src_path[:-4] + ".dat"
        if not (os.path.exists(src_path) and os.path.exists(dat_path)):
            src, dat = krl_pair(args.krl_mb)
            write_once(dat_path, lambda: dat)
            write_once(src_path, lambda: src)
        size = os.path.getsize(src_path) + os.path.getsize(dat_path)
        inputs.append((f"KRL pair {size / 1e6:.0f} MB", src_path, size, "E6POS", dat_path, False))

    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}, {os.cpu_count()} cores")
    print(f"CPU time: median of {args.runs}; peak: largest resident set of the runs")
    print()
    print("| input | command | CPU s | MB/s | peak MB | peak / file | vs baseline |")
    print("|---|---|---:|---:|---:|---:|---|", flush=True)

    def row(label: str, cmd: str, t: float, m: int, mb: float, note: str) -> None:
        rate = f"{mb / t:.0f}" if t > 0 else "∞"
        print(f"| {label} | {cmd} | {t:.3f} | {rate} | {m / 1e6:.0f} | {m / 1e6 / mb:.1f}× | {note} |", flush=True)

    for label, path, size, pattern, grep_file, rapid in inputs:
        mb = size / 1e6
        grep_t, grep_m = measure(["grep", "-c", pattern, grep_file], args.runs)
        row(label, f"grep -c {pattern}", grep_t, grep_m, mb, "")
        py_t = None
        if rapid:
            py_t, py_m = measure(
                [sys.executable, os.path.join(ROOT, "benches", "regex_baseline.py"), path, os.path.join(out_dir, "regex.mod")],
                args.runs,
            )
            row(label, "regex_baseline.py", py_t, py_m, mb, "")
        scan_t = None
        if rapid and os.path.exists(SCAN):
            scan_t, scan_m = measure([SCAN, path], args.runs)
            row(label, "robtarget_scan", scan_t, scan_m, mb, f"{scan_t / grep_t:.1f}× grep")
        commands = {
            "check": lambda exe: [exe, "check", path],
            "inspect --format json": lambda exe: [exe, "inspect", "--format", "json", path],
            "correct": lambda exe: [exe, "correct", path, "--cell", cell, "--robot", "r1", "--out-dir", OUT],
        }
        for cmd, argv_of in commands.items():
            measured = measure_alternating([argv_of(exe) for _, exe in bins], args.runs, args.work)
            for (name, _), (t, m) in zip(bins, measured):
                if cmd == "check":
                    note = f"{t / grep_t:.1f}× grep" + (f", {t / scan_t:.1f}× robtarget_scan" if scan_t else "")
                elif cmd == "correct" and py_t is not None:
                    note = f"{py_t / t:.1f}× faster than regex" if t < py_t else f"{t / py_t:.1f}× slower than regex"
                else:
                    note = ""
                row(label, f"{name} {cmd}", t, m, mb, note)

    print()
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")

if __name__ == "__main__":
    main()
