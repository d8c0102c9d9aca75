#!/usr/bin/env python3
"""Write the example of README's "Groom your own mesh": pebble.obj and stripes.png beside this file.

Run once; both files are committed. Standard library only (zlib), so it runs anywhere.

pebble.obj: an egg-shaped pebble about 1.2 units long (x), 0.7 tall (y) and 0.8 deep (z), with uv:
u runs once around the long axis, v from the -x end (0) to the +x end (1). The positions are
shared across the uv seam and at the two poles, the uv corners are not (OBJ indexes them apart).

stripes.png: 128 x 64 8-bit sRGB RGB, wavy orange and dark brown bands across v (rows), seamless
in u. Colours are written as sRGB values, as a paint program saves them.
"""
import math
import pathlib
import struct
import zlib

HERE = pathlib.Path(__file__).resolve().parent
RINGS = 24  # steps from pole to pole
SEGMENTS = 48  # steps around the long axis


def point(t: float, phi: float) -> tuple:
    """t in [0, 1] from the -x pole to the +x pole, phi around x; an egg, fatter towards +x."""
    theta = math.pi * t
    x = -0.6 * math.cos(theta)
    ring = math.sin(theta) * (1.0 + 0.12 * math.cos(theta - math.pi))
    return (x, 0.35 * ring * math.cos(phi), 0.4 * ring * math.sin(phi))


def write_obj(path: pathlib.Path) -> None:
    lines = ["# spotshell example: an egg-shaped pebble with uv (examples/groom/make_example.py)"]
    # Positions: the -x pole, RINGS - 1 rings of SEGMENTS, the +x pole (1-based indices).
    lines.append("v %.5f %.5f %.5f" % point(0.0, 0.0))
    for j in range(1, RINGS):
        for i in range(SEGMENTS):
            lines.append("v %.5f %.5f %.5f" % point(j / RINGS, 2.0 * math.pi * i / SEGMENTS))
    lines.append("v %.5f %.5f %.5f" % point(1.0, 0.0))
    last = 2 + (RINGS - 1) * SEGMENTS

    def pos(j: int, i: int) -> int:
        if j == 0:
            return 1
        if j == RINGS:
            return last
        return 2 + (j - 1) * SEGMENTS + i % SEGMENTS

    # uv: a (SEGMENTS + 1) x (RINGS + 1) grid, the seam column doubled.
    for j in range(RINGS + 1):
        for i in range(SEGMENTS + 1):
            lines.append("vt %.5f %.5f" % (i / SEGMENTS, j / RINGS))

    def uv(j: int, i: int) -> int:
        return 1 + j * (SEGMENTS + 1) + i

    # Counter-clockwise seen from outside: phi turns from +y to +z, t runs towards +x.
    for j in range(RINGS):
        for i in range(SEGMENTS):
            corners = [(j, i), (j, i + 1), (j + 1, i + 1), (j + 1, i)]
            if j == 0:
                corners = [(0, i), (1, i + 1), (1, i)]
            elif j == RINGS - 1:
                corners = [(j, i), (j, i + 1), (RINGS, i)]
            lines.append("f " + " ".join("%d/%d" % (pos(a, b), uv(a, b)) for a, b in corners))
    path.write_text("\n".join(lines) + "\n")


def chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def write_png(path: pathlib.Path, width: int = 128, height: int = 64) -> None:
    orange = (235, 150, 40)
    brown = (45, 28, 18)
    rows = b""
    for row in range(height):
        v = 1.0 - (row + 0.5) / height  # uv's v points up: row 0 is the top of the image
        rows += b"\x00"
        for col in range(width):
            u = (col + 0.5) / width
            wave = math.sin(2.0 * math.pi * (7.0 * v + 0.12 * math.sin(2.0 * math.pi * 3.0 * u)))
            k = min(1.0, max(0.0, 0.5 + 2.5 * wave))  # soft band edges
            rows += bytes(round(b + (a - b) * k) for a, b in zip(orange, brown))
    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))  # 8-bit RGB
           + chunk(b"sRGB", b"\x00")  # perceptual: the values are sRGB-encoded
           + chunk(b"IDAT", zlib.compress(rows, 9))
           + chunk(b"IEND", b""))
    path.write_bytes(png)


def main() -> None:
    write_obj(HERE / "pebble.obj")
    write_png(HERE / "stripes.png")
    for name in ("pebble.obj", "stripes.png"):
        print(f"wrote {HERE / name} ({(HERE / name).stat().st_size} bytes)")


if __name__ == "__main__":
    main()
