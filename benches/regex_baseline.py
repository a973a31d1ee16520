#!/usr/bin/env python3
"""The baseline `trackfix correct` is measured against: a plain regex rewrite.

Applies one fixed transform to every robtarget of a RAPID module: the position is moved by a
fixed offset (x + 0.125, y - 0.250, z + 0.500 mm), written with the decimals it had, every other
byte kept. It knows nothing of work objects, skids, tools or refusals — it is the fastest
"transform" a script can do, which is what makes it a fair floor for a real one.

    python3 benches/regex_baseline.py IN.mod OUT.mod
"""

import re
import sys

OFFSET = (0.125, -0.250, 0.500)
NUM = rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
# `robtarget name := [[x, y, z], ...` — the three numbers of the position.
TARGET = re.compile(
    rb"(robtarget\s+\w+\s*:=\s*\[\s*\[\s*)(" + NUM + rb")(\s*,\s*)(" + NUM + rb")(\s*,\s*)(" + NUM + rb")",
    re.IGNORECASE,
)


def decimals(text: bytes) -> int:
    dot = text.find(b".")
    return 0 if dot < 0 else len(text) - dot - 1


def moved(text: bytes, delta: float) -> bytes:
    places = max(decimals(text), 3)
    return b"%.*f" % (places, float(text) + delta)


def rewrite(m: re.Match) -> bytes:
    head, x, s1, y, s2, z = m.groups()
    return b"".join(
        (head, moved(x, OFFSET[0]), s1, moved(y, OFFSET[1]), s2, moved(z, OFFSET[2]))
    )


def main() -> None:
    src, dst = sys.argv[1], sys.argv[2]
    with open(src, "rb") as f:
        data = f.read()
    out, count = TARGET.subn(rewrite, data)
    with open(dst, "wb") as f:
        f.write(out)
    print(f"{count} robtargets moved", file=sys.stderr)


if __name__ == "__main__":
    main()
