#!/usr/bin/env python3
"""Run trackfix over every controller backup under a directory and print one table.

    python3 scripts/corpus-run.py DIR [--bin target/release/trackfix] [--cell samples/cell_rules.toml]
                                      [--robot r1] [--to r2] [--json OUT.json]

A backup unit is a RobotStudio task folder (a folder holding `PROGMOD` and/or `SYSMOD`) or a KSS
robot tree (a folder holding `Program/` and/or `System/$config.dat`). Each unit is run on its own
with `check`, `inspect`, `correct --skip-unsupported --out-dir` and `transfer --skip-unsupported
--out-dir` (outputs go to a temporary folder that is removed), all with `--format json`, and the
table gives per unit: files, error findings (parse errors), positions, targets with a real track
position, targets changed, refusals by kind and the share transformed. Not part of `cargo test`:
it needs real backups, which are not ours and are never copied into the project.
"""

import argparse
import collections
import json
import os
import re
import subprocess
import sys
import tempfile


def find_units(root):
    units = []
    for dirpath, dirnames, filenames in os.walk(root):
        names = set(dirnames)
        lower = {n.lower() for n in dirnames}
        if "progmod" in lower or "sysmod" in lower:
            units.append(("rapid", dirpath))
            dirnames[:] = []
        elif "Program" in names or os.path.isfile(os.path.join(dirpath, "System", "$config.dat")):
            if os.path.basename(dirpath).upper().startswith("R") or "System" in names:
                units.append(("krl", dirpath))
                dirnames[:] = []
        dirnames.sort()
    return units


def run_json(cmd):
    """Runs a trackfix command; returns (exit code, parsed JSON or None, stderr)."""
    p = subprocess.run(cmd, capture_output=True, timeout=900)
    out = p.stdout.decode("utf-8", "replace")
    doc = None
    start = out.find("\n{") + 1 if not out.startswith("{") else 0
    if "{" in out:
        try:
            doc = json.loads(out[start:])
        except json.JSONDecodeError:
            doc = None
    return p.returncode, doc, p.stderr.decode("utf-8", "replace")


def construct(message):
    """The kind of a finding: its message with quoted names and numbers blanked."""
    m = re.sub(r"`[^`]*`", "`…`", message)
    return re.sub(r"\d+(\.\d+)?", "N", m)[:70]


def is_track(pos):
    s = pos.get("skid")
    return s is not None and abs(s) < 8e9 and pos.get("x") is not None


def run_unit(args, lang, path):
    row = {"unit": os.path.relpath(path, args.dir), "lang": lang}
    rc, chk, err = run_json([args.bin, "check", path, "--format", "json"])
    errors = collections.Counter()
    if chk:
        row["files"] = chk["summary"]["files"]
        row["round_trips"] = chk["summary"].get("round_trips")
        for f in chk["files"]:
            for x in f["findings"]:
                if x["severity"] == "error":
                    errors[construct(x["message"])] += 1
    row["errors"] = dict(errors)
    rc, ins, err = run_json([args.bin, "inspect", path, "--format", "json"])
    positions = [p for f in (ins or {}).get("files", []) for p in f.get("positions", [])]
    row["positions"] = len(positions)
    row["track_targets"] = sum(1 for p in positions if is_track(p))
    row["opaque"] = sum(f.get("opaque", 0) for f in (ins or {}).get("files", []))
    with tempfile.TemporaryDirectory() as out:
        base = ["--cell", args.cell, "--skip-unsupported", "--format", "json"]
        rc, cor, err = run_json(
            [args.bin, "correct", path, "--robot", args.robot, "--out-dir", out + "/c"] + base
        )
        row["correct_exit"] = rc
        kinds = collections.Counter(r["kind"] for r in (cor or {}).get("refusals", []))
        row["refusals"] = dict(kinds)
        row["changed"] = (cor or {}).get("totals", {}).get("targets_changed", 0)
        rc, tra, err = run_json(
            [args.bin, "transfer", path, "--from", args.robot, "--to", args.to,
             "--out-dir", out + "/t"] + base
        )
        row["transfer_exit"] = rc
        row["transfer_changed"] = (tra or {}).get("totals", {}).get("targets_changed", 0)
    total = row["changed"] + sum(kinds.values())
    row["targets"] = total
    row["pct"] = 100.0 * row["changed"] / total if total else None
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir")
    ap.add_argument("--bin", default="target/release/trackfix")
    ap.add_argument("--cell", default="samples/cell_rules.toml")
    ap.add_argument("--robot", default="r1")
    ap.add_argument("--to", default="r2")
    ap.add_argument("--json", help="also write every row as JSON here")
    args = ap.parse_args()
    units = find_units(args.dir)
    if not units:
        sys.exit(f"{args.dir}: no RobotStudio task folder or KSS robot tree found")
    rows = []
    for lang, path in units:
        rows.append(run_unit(args, lang, path))
        print(f"… {rows[-1]['unit']}", file=sys.stderr)
    head = f"{'unit':58} {'lang':5} {'files':>5} {'err':>4} {'pos':>6} {'track':>6} {'targets':>7} {'changed':>7} {'%':>5} {'c/t exit':>8}"
    print(head)
    for r in rows:
        pct = "-" if r["pct"] is None else f"{r['pct']:.0f}"
        print(f"{r['unit'][-58:]:58} {r['lang']:5} {r.get('files', 0):>5} {sum(r['errors'].values()):>4} "
              f"{r['positions']:>6} {r['track_targets']:>6} {r['targets']:>7} {r['changed']:>7} {pct:>5} "
              f"{r['correct_exit']:>4}/{r['transfer_exit']}")
    for lang in ("rapid", "krl"):
        sel = [r for r in rows if r["lang"] == lang]
        if not sel:
            continue
        t = sum(r["targets"] for r in sel)
        c = sum(r["changed"] for r in sel)
        kinds = collections.Counter()
        errors = collections.Counter()
        for r in sel:
            kinds.update(r["refusals"])
            errors.update(r["errors"])
        print(f"\n{lang}: {len(sel)} units, {sum(r.get('files', 0) for r in sel)} files, "
              f"{sum(r['positions'] for r in sel)} positions ({sum(r['track_targets'] for r in sel)} "
              f"with a track position), {c} of {t} targets transformed"
              f" ({100.0 * c / t if t else 0:.1f} %), {sum(r['opaque'] for r in sel)} opaque nodes")
        # Targets with no track position (9E9, none written) and joint targets are not the
        # track's to correct: the share that matters is of the others.
        off_track = sum(kinds[k] for k in ("skid-not-connected", "skid-missing", "joint-target"))
        on_track = t - off_track
        print(f"  on the track: {c} of {on_track} transformed"
              f" ({100.0 * c / on_track if on_track else 0:.1f} %)")
        for k, n in kinds.most_common():
            print(f"  refused {k:28} {n:>6}")
        for k, n in errors.most_common():
            print(f"  error   {n:>4}  {k}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
