#!/usr/bin/env python3
"""Write presets/textures/density_spots.png, the 64x64 8-bit grey density map that
presets/README.md uses as its image-field example and tests/noise/preset_test.cpp reads back.

Run once; the PNG is committed. Standard library only (zlib), so it runs anywhere. The pattern is
a closed formula so the test can recompute any texel:
    value(col, row) = round(255 * (0.5 + 0.5 * sin(2 pi col / 32) * cos(2 pi row / 16)))
with row 0 the top row of the image.
"""
import math
import pathlib
import struct
import zlib

SIZE = 64


def texel(col: int, row: int) -> int:
    return round(255 * (0.5 + 0.5 * math.sin(2 * math.pi * col / 32) * math.cos(2 * math.pi * row / 16)))


def chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def main() -> None:
    rows = b"".join(b"\x00" + bytes(texel(c, r) for c in range(SIZE)) for r in range(SIZE))
    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 8, 0, 0, 0, 0))  # 8-bit grey
           + chunk(b"IDAT", zlib.compress(rows, 9))
           + chunk(b"IEND", b""))
    out = pathlib.Path(__file__).resolve().parent.parent / "presets" / "textures" / "density_spots.png"
    out.write_bytes(png)
    print(f"wrote {out} ({len(png)} bytes)")


if __name__ == "__main__":
    main()
