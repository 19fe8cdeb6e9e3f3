#!/usr/bin/env python3
"""Writes scenes/models/cloth_000.obj … cloth_007.obj: a 13 × 13-vertex sheet
(288 triangles, one topology) rippling over eight frames, the OBJ sequence of
scenes/shadowfield_deform_seq.toml. Deterministic (stdlib only, fixed digits):
`python3 scripts/make_cloth_sequence.py` rewrites the same bytes."""

import math
import os

FRAMES = 8
N = 13  # vertices per side
HALF = 0.8  # the sheet spans [-HALF, HALF] in x and z
HEIGHT = 0.9


def vertex(i, j, k):
    u, v = i / (N - 1), j / (N - 1)
    phase = 2.0 * math.pi * k / FRAMES
    # A wave along x whose amplitude grows along z, and a sag in the middle.
    y = HEIGHT + 0.22 * math.sin(math.pi * 1.5 * u - phase) * v
    y -= 0.12 * math.sin(math.pi * u) * math.sin(math.pi * v) * (1.0 + math.cos(phase)) / 2.0
    return (-HALF + 2.0 * HALF * u, y, -HALF + 2.0 * HALF * v)


def write(path, k):
    lines = [f"# cloth frame {k} of {FRAMES}: scripts/make_cloth_sequence.py", "o cloth"]
    for j in range(N):
        for i in range(N):
            x, y, z = vertex(i, j, k)
            lines.append(f"v {x:.5f} {y:.5f} {z:.5f}")
    for j in range(N - 1):
        for i in range(N - 1):
            a = j * N + i + 1  # OBJ indices are 1-based
            b, c, d = a + 1, a + N + 1, a + N
            lines += [f"f {a} {d} {c}", f"f {a} {c} {b}"]
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def main():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "models")
    for k in range(FRAMES):
        write(os.path.join(root, f"cloth_{k:03}.obj"), k)


if __name__ == "__main__":
    main()
