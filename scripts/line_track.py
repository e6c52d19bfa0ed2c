#!/usr/bin/env python3
"""Draws examples/line_following/worlds/textures/track.png: a black line 24 mm wide on white,
along a stadium (two 0.4 m straights joined by half circles of 0.25 m radius) centred on a
1 m x 1 m floor, 2 mm per pixel. The image's top row lies at the floor's +y edge, its first
column at -x, as RectangleArena maps an image seen from above.

Usage: scripts/line_track.py [OUT.png]"""

import math
import struct
import sys
import zlib

SIZE = 500  # pixels per side: 1 m / 2 mm
HALF_STRAIGHT = 0.2  # m
RADIUS = 0.25  # m
WIDTH = 0.024  # m


def on_line(x: float, y: float) -> bool:
    """Whether the floor point (x, y) lies on the line: its distance to the stadium's centre
    segment is within WIDTH / 2 of RADIUS."""
    dx = max(abs(x) - HALF_STRAIGHT, 0.0)
    return abs(math.hypot(dx, y) - RADIUS) <= WIDTH / 2


def png(rows: list[bytes]) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    raw = b"".join(b"\x00" + row for row in rows)
    header = struct.pack(">IIBBBBB", SIZE, SIZE, 8, 0, 0, 0, 0)  # 8-bit grey
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def main() -> None:
    out = sys.argv[1] if len(sys.argv) > 1 else "examples/line_following/worlds/textures/track.png"
    rows = []
    for row in range(SIZE):
        y = 0.5 - (row + 0.5) / SIZE
        rows.append(
            bytes(0 if on_line((col + 0.5) / SIZE - 0.5, y) else 255 for col in range(SIZE))
        )
    with open(out, "wb") as f:
        f.write(png(rows))


if __name__ == "__main__":
    main()
